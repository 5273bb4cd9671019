"""The Xylo goal on a written artefact (not run in CI): XyloSim runs the artefact's spec.npz unchanged and
gives the output spikes of ``snncc emulate``; the artefact's argmax agreement with the float graph.

    snncc compile tests/data/nir/braille_noDelay_noBias_subtract.nir --target xylo --dt 1e-4 \\
        --reset subtract -o braille.xylo
    python bench/studies/xylo_artefact_goal.py braille.xylo [--model ...nir] [--dt 1e-4] [--reset subtract]
        [--samples 1000] [--steps 256] [--density 0.08] [--seed 0] [--out bench/studies/results/xylo_artefact_goal.json]

Inputs: seeded random spike trains (SYNTHETIC), the same as bench/studies/xylo_side_by_side.py's. snncc's side
runs through ``snncc.api.emulate`` (what ``snncc emulate --target xylo`` runs); XyloSim (xylosim 0.1.3,
driven by tests/xylo/oracle.py) is fed the manifest's timing by hand. Agreement: over the samples whose
float output has one clear winner (the others counted beside), with the 95 % Wilson interval.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from bench.studies.xylo_bench_io import agreement, load, model_arguments, write_result  # noqa: E402
from tests.xylo.oracle import XyloSimOracle  # noqa: E402
from snncc import api  # noqa: E402
from snncc.ir.nodes import LIF  # noqa: E402
from snncc.ir.simulate import simulate  # noqa: E402
from snncc.targets.kit.agreement import random_inputs  # noqa: E402
from snncc.targets.xylo.spec import XyloSpec  # noqa: E402
from snncc.threads import one_thread  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("artefact")
    model_arguments(ap)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(ROOT / "bench" / "studies" / "results" / "xylo_artefact_goal.json"))
    args = ap.parse_args()

    art = Path(args.artefact)
    manifest = json.loads((art / "manifest.json").read_text())
    x = random_inputs(args.samples, args.steps, manifest["network"]["inputs"], args.density, args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        np.save(Path(tmp) / "x.npy", x)
        t0 = time.perf_counter()
        api.emulate(art, input=Path(tmp) / "x.npy", output=Path(tmp) / "out.npz", target="xylo")
        snncc_s = time.perf_counter() - t0
        with np.load(Path(tmp) / "out.npz", allow_pickle=False) as got:
            ours = got["output_spikes"]
    pad, lag = manifest["feed"]["input_pad"], manifest["feed"]["output_lag"]
    fed = np.zeros((x.shape[0], x.shape[1] + max(pad, lag), x.shape[2]), np.uint8)
    fed[:, pad:pad + x.shape[1]] = x
    t0 = time.perf_counter()
    theirs = XyloSimOracle(XyloSpec.load_npz(art / "spec.npz")).run(fed).output_spikes[:, lag:lag + x.shape[1]]
    xylosim_s = time.perf_counter() - t0
    identical = bool(np.array_equal(ours, theirs))
    graph = load(args)
    last = [n for n, op in graph.items() if isinstance(op, LIF)][-1]
    with one_thread():
        float_counts = np.asarray(simulate(graph, x, record="spikes").spikes[last]).sum(axis=1)
    agr = agreement(ours.sum(axis=1), float_counts)
    result = {"artefact": args.artefact, "model": args.model, "rule": manifest["quantization"]["rule"],
              "inputs": f"{args.samples} seeded random spike trains (density {args.density}, seed {args.seed}), "
                        f"{args.steps} steps (SYNTHETIC)",
              "xylosim_equals_snncc_emulate": identical, "differing_entries": int(np.sum(ours != theirs)),
              "output_spikes_total": int(ours.sum()), "agreement": agr.as_dict(),
              "snncc_emulate_seconds": snncc_s, "xylosim_seconds": xylosim_s}
    print(f"XyloSim on spec.npz == snncc emulate: {identical} ({result['differing_entries']} differing entries, "
          f"{result['output_spikes_total']} output spikes)")
    print(f"agreement with the float graph [{result['rule']}]: {agr.line()}")
    write_result(args.out, result)


if __name__ == "__main__":
    main()
