"""Where a Xylo artefact loses agreement: its hidden layer or its readout (not run in CI).

    snncc compile tests/data/nir/braille_noDelay_noBias_subtract.nir --target xylo --dt 1e-4 \\
        --reset subtract --replicas 4 -o b4.xylo
    python bench/studies/xylo_loss_by_layer.py b4.xylo [--model ...nir] [--dt 1e-4] [--reset subtract]
        [--samples 1000] [--seeds 0,5,6,7,8] [--out bench/studies/results/xylo_loss_by_layer.json]

For a model with one hidden population read by a Dense + LIF readout (the Braille RSNN), on seeded random
spike trains (SYNTHETIC; seed 0 is the goal's held-out set, others are further draws) four figures of argmax
agreement with the float graph (clear-winner rule, 95 % Wilson interval):

    chip                       the artefact in snncc's bit-exact emulator (equal to XyloSim)
    float readout, chip hidden the float graph's readout driven by the chip's hidden spikes (with replicas: the
                               mean of the copies' spikes, as the chip's output neurons read them)
    each copy                  the same with one copy's spikes
    chip readout, float hidden the chip's output neurons (integer rules) driven by the float graph's hidden spikes
                               (in every copy)

Both substitutions are checked every run: the float readout driven by the float hidden spikes must give the
float graph's output spikes, and the chip readout driven by the chip's hidden spikes the emulator's output.
With several seeds the figures are also pooled over all samples.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from bench.studies.xylo_bench_io import agreement, load, model_arguments, write_result  # noqa: E402
from snncc.ir.nodes import LIF, Dense  # noqa: E402
from snncc.ir.simulate import simulate  # noqa: E402
from snncc.targets.kit.agreement import random_inputs  # noqa: E402
from snncc.targets.xylo.emulation.emulator import decay, effective_weights, emulate, sat16  # noqa: E402
from snncc.targets.xylo.spec import XyloSpec  # noqa: E402
from snncc.targets.xylo.artefact.read import read_artefact  # noqa: E402
from snncc.threads import one_thread  # noqa: E402


def readout_parts(graph) -> tuple[str, Dense, str]:
    """(hidden LIF name, its Dense, the readout LIF's name): the chain hidden -> Dense -> LIF this bench handles."""
    lifs = [n for n, op in graph.items() if isinstance(op, LIF)]
    (dense_name,) = graph.predecessors(lifs[-1])
    dense = graph.node(dense_name)
    (hidden,) = graph.predecessors(dense_name)
    out = graph.node(lifs[-1])
    ok = (isinstance(dense, Dense) and hidden in lifs and out.bias is None and out.discretisation == "euler"
          and out.reset == "subtract" and out.standard_spikes and out.refractory <= 1
          and graph.delay(hidden, dense_name) == 0 and graph.delay(dense_name, lifs[-1]) == 0)
    if not ok:
        raise SystemExit("this bench handles one hidden LIF read by Dense -> LIF (euler, subtract, no bias, delay 0)")
    return hidden, dense, lifs[-1]


def float_readout(s: np.ndarray, dense: Dense, lif: LIF, dt: float) -> np.ndarray:
    """The IR's forward-Euler CUBA readout: I = alpha I + W s, V = beta V + I, spike on V > theta, V -= theta."""
    alpha, beta = 1.0 - dt / np.asarray(lif.tau_syn), 1.0 - dt / np.asarray(lif.tau_mem)
    w, theta = np.asarray(dense.weight, np.float64), np.asarray(lif.threshold, np.float64)
    i = np.zeros((s.shape[0], lif.n))
    v = np.zeros_like(i)
    out = np.zeros((s.shape[0], s.shape[1], lif.n))
    for t in range(s.shape[1]):
        i = alpha * i + s[:, t] @ w.T
        v = beta * v + i
        fired = v > theta
        v = np.where(fired, v - theta, v)
        out[:, t] = fired
    return out


def chip_readout(spec: XyloSpec, events: np.ndarray) -> np.ndarray:
    """The output neurons under the chip's integer rules (docs/xylo.md), fed hidden ``events`` (B, T, N) of each
    chip step (delivered the step after), as the emulator runs them."""
    _, _, w_out = effective_weights(spec)
    b, steps, n = events.shape
    dash_syn, dash_mem = spec.dash_syn_out.astype(np.int64), spec.dash_mem_out.astype(np.int64)
    bias, theta = spec.bias_out.astype(np.int64), spec.threshold_out.astype(np.int64)
    i = np.zeros((b, spec.n_out), np.int64)
    v = np.zeros_like(i)
    prev = np.zeros((b, n), np.int64)
    out = np.zeros((b, steps, spec.n_out), np.uint8)
    for t in range(steps):
        i = sat16(i + prev[:, n - spec.n_oen:] @ w_out)
        i = i - decay(i, dash_syn)
        v = sat16(v + sat16(sat16(-decay(v, dash_mem) + i) + bias))
        fired = v >= theta
        v = np.where(fired, v - theta, v)
        out[:, t] = fired
        prev = events[:, t].astype(np.int64)
    return out


def one_seed(graph, spec: XyloSpec, manifest: dict, samples: int, seed: int, density: float,
             steps: int = 256) -> dict[str, dict]:
    """The figures of the module docstring on ``samples`` seeded random spike trains of ``seed``."""
    hidden, dense, last = readout_parts(graph)
    lif = graph.node(last)
    q = manifest["quantization"]
    (pop,) = [p for p in q["populations"] if p["name"] == hidden and p["role"] == "hidden"]
    copies = int(pop.get("copies", 1))
    cells = np.arange(*pop["neurons"]).reshape(copies, -1)
    pad, lag = manifest["feed"]["input_pad"], manifest["feed"]["output_lag"]
    at = pad + int(q["timing"]["shifts"][hidden])          # chip step of the hidden population's IR step 0
    width = manifest["network"]["inputs"]
    x = random_inputs(samples, steps, width, density, seed)
    with one_thread():
        ref = simulate(graph, x, record="spikes")
    h_float = np.asarray(ref.spikes[hidden])
    o_float = np.asarray(ref.spikes[last])
    counts = o_float.sum(axis=1)
    if not np.array_equal(float_readout(h_float, dense, lif, graph.dt), o_float):
        raise SystemExit("internal check failed: the float readout does not reproduce the float graph")
    fed = np.zeros((samples, steps + max(pad, lag) + at, width), np.uint8)
    fed[:, pad:pad + steps] = x
    run = emulate(spec, fed, record=True)
    if not np.array_equal(chip_readout(spec, run.spikes), run.output_spikes):
        raise SystemExit("internal check failed: the chip readout does not reproduce the emulator")
    chip = run.output_spikes[:, lag:lag + steps].sum(axis=1)
    h_chip = run.spikes[:, at:at + steps][:, :, cells].astype(np.float64)        # (B, T, copies, n)
    figures = {"chip": agreement(chip, counts),
               "float readout, chip hidden (copies' mean)":
                   agreement(float_readout(h_chip.mean(axis=2), dense, lif, graph.dt).sum(axis=1), counts)}
    if copies > 1:
        for k in range(copies):
            figures[f"float readout, chip hidden copy {k}"] = agreement(
                float_readout(h_chip[:, :, k], dense, lif, graph.dt).sum(axis=1), counts)
    events = np.zeros(run.spikes.shape, np.uint8)
    for row in cells:
        events[:, at:at + steps, row] = h_float
    figures["chip readout, float hidden"] = agreement(
        chip_readout(spec, events)[:, lag:lag + steps].sum(axis=1), counts)
    return {"figures": figures, "counts": counts, "outputs": {"chip": chip}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("artefact")
    model_arguments(ap)
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--out", default=str(ROOT / "bench" / "studies" / "results" / "xylo_loss_by_layer.json"))
    args = ap.parse_args()

    art = Path(args.artefact)
    written = read_artefact(art)                 # manifest and spec.npz, checked against the recorded hash
    manifest, spec = written.manifest, written.spec
    graph = load(args)
    seeds = [int(s) for s in args.seeds.split(",")]
    result = {"artefact": str(art), "model": args.model, "rule": manifest["quantization"]["rule"],
              "inputs": f"{args.samples} seeded random spike trains per seed (density {args.density}), "
                        f"{args.steps} steps "
                        "(SYNTHETIC)", "seeds": {}}
    pooled_chip, pooled_counts = [], []
    for seed in seeds:
        got = one_seed(graph, spec, manifest, args.samples, seed, args.density, args.steps)
        result["seeds"][str(seed)] = {k: a.as_dict() for k, a in got["figures"].items()}
        pooled_chip.append(got["outputs"]["chip"])
        pooled_counts.append(got["counts"])
        print(f"seed {seed}:")
        for name, agr in got["figures"].items():
            print(f"  {name}: {agr.line()}")
    if len(seeds) > 1:
        pooled = agreement(np.concatenate(pooled_chip), np.concatenate(pooled_counts))
        result["pooled_chip"] = pooled.as_dict()
        print(f"chip, pooled over seeds {args.seeds}: {pooled.line()}")
    write_result(args.out, result)


if __name__ == "__main__":
    main()
