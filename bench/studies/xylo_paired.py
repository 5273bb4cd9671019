"""Two or more Xylo artefacts of one model, sample by sample on the same inputs (not run in CI).

    python bench/studies/xylo_paired.py b4.xylo b4both.xylo [--model ...nir] [--dt 1e-4] [--reset subtract]
        [--samples 1000] [--seeds 0,5,6,7,8,9,10,11] [--out bench/studies/results/xylo_paired.json]

Each artefact's spec.npz (read with its hash checked) runs in snncc's bit-exact emulator on seeded random spike
trains (SYNTHETIC; seed 0 is the goal's held-out set, the others further draws). Per seed and pooled: argmax
agreement with the float graph (clear-winner rule, 95 % Wilson interval). Against the first artefact, on the same
clear-winner samples: the samples only this one gets right (+), only the first gets right (-), and the exact
two-sided McNemar p of that split -- a paired test, far more sensitive than comparing two intervals.
"""

from __future__ import annotations

import argparse
import sys
from math import comb
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from bench.studies.xylo_bench_io import agreement, load, model_arguments, write_result  # noqa: E402
from snncc.ir.nodes import LIF  # noqa: E402
from snncc.ir.simulate import simulate  # noqa: E402
from snncc.targets.kit.agreement import random_inputs  # noqa: E402
from snncc.targets.kit.agreement import decided, wilson_interval  # noqa: E402
from snncc.targets.xylo.emulation.emulator import emulate  # noqa: E402
from snncc.targets.xylo.artefact.read import read_artefact  # noqa: E402
from snncc.threads import one_thread  # noqa: E402


def mcnemar(better: int, worse: int) -> float:
    """Exact two-sided McNemar p: the smaller of the two discordant counts under Binomial(n, 1/2)."""
    n = better + worse
    if n == 0:
        return 1.0
    return min(1.0, 2 * sum(comb(n, i) for i in range(min(better, worse) + 1)) / 2 ** n)


def chip_counts(written, x: np.ndarray) -> np.ndarray:
    """Output counts (B, classes) of a written artefact on IR inputs ``x``, fed with the manifest's timing."""
    pad, lag = written.input_pad, written.output_lag
    steps = x.shape[1]
    fed = np.zeros((x.shape[0], steps + max(pad, lag), x.shape[2]), np.uint8)
    fed[:, pad:pad + steps] = x
    return emulate(written.spec, fed).output_spikes[:, lag:lag + steps].sum(axis=1)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("artefacts", nargs="+")
    model_arguments(ap)
    ap.add_argument("--seeds", default="0,5,6,7,8,9,10,11")
    ap.add_argument("--out", default=str(ROOT / "bench" / "studies" / "results" / "xylo_paired.json"))
    args = ap.parse_args()
    graph = load(args)
    written = [read_artefact(a) for a in args.artefacts]
    width = written[0].manifest["network"]["inputs"]
    seeds = [int(s) for s in args.seeds.split(",")]
    last = [n for n, op in graph.items() if isinstance(op, LIF)][-1]      # the readout population
    hits: list[list[np.ndarray]] = [[] for _ in written]
    result = {"model": args.model, "inputs": f"{args.samples} seeded random spike trains per seed (density "
              f"{args.density}), {args.steps} steps (SYNTHETIC)", "seeds": seeds, "artefacts": []}
    per_seed: list[dict[str, dict]] = [{} for _ in written]
    for seed in seeds:
        x = random_inputs(args.samples, args.steps, width, args.density, seed)
        with one_thread():
            ref = simulate(graph, x, record="spikes")
        counts = np.asarray(ref.spikes[last]).sum(axis=1)
        mask = decided(counts)
        for i, w in enumerate(written):
            got = chip_counts(w, x)
            per_seed[i][str(seed)] = agreement(got, counts).as_dict()
            hits[i].append((np.argmax(got, axis=1) == np.argmax(counts, axis=1))[mask])
    first = np.concatenate(hits[0])
    for i, (path, w) in enumerate(zip(args.artefacts, written)):
        h = np.concatenate(hits[i])
        lo, hi = wilson_interval(int(h.sum()), h.size)
        better, worse = int((h & ~first).sum()), int((~h & first).sum())
        row = {"artefact": path, "rule": w.manifest["quantization"]["rule"], "pooled": float(h.mean()),
               "low": lo, "high": hi, "counted": int(h.size), "per_seed": per_seed[i],
               "vs_first": {"only_this": better, "only_first": worse, "mcnemar_p": mcnemar(better, worse)}}
        result["artefacts"].append(row)
        seeds_line = ", ".join(f"{s}: {v['share']:.3f}" for s, v in per_seed[i].items())
        print(f"{path} ({row['rule']}): pooled {h.mean():.4f} [{lo:.3f}, {hi:.3f}] over {h.size}; per seed {seeds_line}"
              + ("" if i == 0 else f"; vs {args.artefacts[0]}: +{better} -{worse}, McNemar p = {mcnemar(better, worse):.3g}"))
    write_result(args.out, result)


if __name__ == "__main__":
    main()
