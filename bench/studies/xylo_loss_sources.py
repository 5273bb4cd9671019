"""What a relayed Xylo lowering loses to each of its approximations (not run in CI).

    python bench/studies/xylo_loss_sources.py [--model ...nir] [--dt 1e-4] [--reset subtract] [--replicas 1]
        [--samples 1000] [--seeds 5,6] [--relay-factor 100] [--out bench/studies/results/xylo_loss_sources.json]

The graph is lowered twice with the same rule (``--rule``, default relayed): as snncc writes it, and with every
weight left unrounded (``lower(..., rounding="none")``: the same fit, gains, shifts, thresholds, dashes and relays,
the weights as float chip units). On the same seeded random spike trains (SYNTHETIC; default seeds 5 and 6, not
the goal's held-out seed 0) it measures argmax agreement with the float graph (clear-winner rule, 95 % Wilson
interval) of, one approximation removed at a time:

    chip              the written spec dict in snncc's bit-exact emulator (equal to XyloSim)
    twin              its float twin (twin.py): the chip without its integer state arithmetic
    unrounded         the unrounded spec's twin: also without int8 weight rounding
    fine relays       the same with every relay --relay-factor times finer (its threshold and the weights of its
                      events divided by the factor, events per step uncapped): nearly without relay quantization

What ``fine relays`` still loses is the fitted kernels' (identified two-exponential + relayed bases in closed
loop) and the readout's own decays (bench/studies/xylo_loss_by_layer.py splits the readout off).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from bench.studies.xylo_bench_io import agreement, load, model_arguments, write_result  # noqa: E402
from snncc.ir.nodes import LIF  # noqa: E402
from snncc.ir.simulate import simulate  # noqa: E402
from snncc.targets.kit.agreement import random_inputs  # noqa: E402
from snncc.targets.xylo.emulation.emulator import emulate  # noqa: E402
from snncc.targets.xylo.lowering.lower import lower, twin_counts  # noqa: E402
from snncc.targets.xylo.options import XyloOptions, XyloStudyKnobs  # noqa: E402
from snncc.targets.xylo.spec import XyloSpec  # noqa: E402
from snncc.targets.xylo.lowering.twin import spec_graph  # noqa: E402
from snncc.threads import one_thread  # noqa: E402


def twin_emulator(dt: float):
    """(spec dict, chip inputs) -> output spikes of that spec dict's float twin: runs unrounded specs."""
    def run(spec: dict, chip_x: np.ndarray) -> np.ndarray:
        with one_thread():
            return np.asarray(simulate(spec_graph(spec, dt), chip_x, record="spikes").spikes["output"])
    return run


def finer_relays(lowered, factor: float):
    """The twin of ``lowered``'s spec with every relay ``factor`` times finer, its events uncapped."""
    spec = {k: (np.asarray(v, np.float64).copy() if k in ("threshold", "weights_rec", "weights_out") else v)
            for k, v in lowered.spec.items()}
    for rec in lowered.populations:
        if rec.role == "relay":
            a, b = rec.neurons
            spec["threshold"][a:b] /= factor
            spec["weights_rec"][a:b] /= factor
            spec["weights_out"][a:b] /= factor
    twin = spec_graph(spec, lowered.dt)
    twin.node("hidden").max_spikes = 1 << 30
    return twin


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    model_arguments(ap)
    ap.add_argument("--rule", default="relayed")
    ap.add_argument("--replicas", type=int, default=1)
    ap.add_argument("--seeds", default="5,6")
    ap.add_argument("--relay-factor", type=float, default=100.0)
    ap.add_argument("--out", default=str(ROOT / "bench" / "studies" / "results" / "xylo_loss_sources.json"))
    args = ap.parse_args()

    graph = load(args)
    opts = XyloOptions(rule=args.rule, replicas=args.replicas)
    chip_low = lower(graph, opts)
    # the unrounded lowering measures its candidates in the twin and could choose another readout: keep the
    # written one's
    readout = "hidden" if "readout on hidden neurons" in chip_low.rule else "output"
    float_low = lower(graph, opts, XyloStudyKnobs(rounding="none", emulator=twin_emulator(graph.dt), readout=readout))
    if chip_low.rule != float_low.rule:
        raise SystemExit(f"the unrounded lowering chose {float_low.rule!r}, the written one {chip_low.rule!r}")
    fine_twin = finer_relays(float_low, args.relay_factor)
    last = [n for n, op in graph.items() if isinstance(op, LIF)][-1]
    spec = XyloSpec(**chip_low.spec)
    counts: dict[str, list[np.ndarray]] = {"chip": [], "twin": [], "unrounded": [], "fine relays": []}
    reference = []
    for seed in (int(s) for s in args.seeds.split(",")):
        x = random_inputs(args.samples, args.steps, graph.node("input").width, args.density, seed)
        with one_thread():
            reference.append(np.asarray(simulate(graph, x, record="spikes").spikes[last]).sum(axis=1))
        counts["chip"].append(chip_low.read_output(emulate(spec, chip_low.chip_input(x)).output_spikes,
                                                   args.steps).sum(axis=1))
        counts["twin"].append(twin_counts(chip_low.twin, chip_low.timing, x))
        counts["unrounded"].append(twin_counts(float_low.twin, float_low.timing, x))
        counts["fine relays"].append(twin_counts(fine_twin, float_low.timing, x))
    ref = np.concatenate(reference)
    result = {"model": args.model, "rule": chip_low.rule, "unrounded_rule": float_low.rule, "replicas": args.replicas,
              "relay_factor": args.relay_factor,
              "inputs": f"{args.samples} seeded random spike trains per seed {args.seeds} (density {args.density}), "
                        f"{args.steps} steps (SYNTHETIC)", "stages": {}}
    for name, parts in counts.items():
        agr = agreement(np.concatenate(parts), ref)
        result["stages"][name] = agr.as_dict()
        print(f"{name:12s} {agr.line()}")
    write_result(args.out, result)


if __name__ == "__main__":
    main()
