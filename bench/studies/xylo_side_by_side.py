"""Xylo Audio 2 side by side on the NIR paper's Braille graphs: the float graph, Rockpool's own flow in
XyloSim, and snncc's spec in XyloSim, on the same seeded inputs (not run in CI).

For each Braille graph in tests/data/nir that fits the chip, on two input sets:
    random   --samples seeded random spike trains x --steps steps, density --density (SYNTHETIC)
    braille  snncc's synthetic Braille events (generator v2, SYNTHETIC) encoded like the NIR paper's
             inputs: letters Space, A, E, I, O, U, Y; sigma-delta ON and OFF events at threshold 1 merged
             per taxel into 12 channels; the 1.35 s record binned into --steps steps
it reports, against the float graph (snncc's IR reference simulation; with a reset change, the graph as
deployed), argmax agreement over the samples whose float output has one clear winner (a unique non-zero
maximum; the others are counted beside it) with its 95 % Wilson interval, and the output-count
correlation, for:
    snncc <rule>     lower(graph, rule) for direct / single / single-identified / relayed, the network spec run in XyloSim
    snncc auto       what ``rule=auto`` picks (measured in snncc's bit-exact emulator on its own calibration
                     inputs, seed 1, never these)
    rockpool         Rockpool 3.1's flow (bench/studies/xylo_rockpool_flow.py, run in --rockpool-python)
    decays rounded   the float graph with only its decays moved to the nearest 1 - 2^-dash (no chip)
    noise 1 % / 0.3 %  the float graph against itself with every weight x (1 + noise N(0, 1)), mean of 3 draws

    python bench/studies/xylo_side_by_side.py [--samples 1000] [--steps 256] [--density 0.08] [--seed 0]
        [--braille-reps 100] [--calibration 256] [--rockpool-python /work/venvs/rockpool/bin/python]
        [--graphs NAME ...] [--out bench/studies/results/xylo_side_by_side.json]

Needs xylosim 0.1.3 in this environment and Rockpool in a separate one (its nir extra pins nir <= 1.0.4).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from tests.xylo.oracle import XyloSimOracle  # noqa: E402   (xylosim 0.1.3, driven directly)
from bench.studies.xylo_bench_io import agreement  # noqa: E402
from snncc.errors import SnnccError  # noqa: E402
from snncc.frontends import LoadOptions, load_model  # noqa: E402
from snncc.ir.nodes import Dense  # noqa: E402
from snncc.targets.kit.agreement import random_inputs  # noqa: E402
from snncc.targets.kit.reference import perturbed  # noqa: E402
from snncc.targets.xylo.checks.stages import float_counts, rounded_decays  # noqa: E402   (what check measures)
from snncc.targets.xylo.lowering.lower import lower  # noqa: E402
from snncc.targets.xylo.options import XyloOptions, XyloStudyKnobs  # noqa: E402
from snncc.targets.xylo.spec import XyloSpec  # noqa: E402

GRAPHS = {  # file -> (load options, allow_reset_change)
    "braille_noDelay_noBias_subtract.nir": (dict(dt=1e-4, reset="subtract"), False),
    "braille_zero_2023.nir": (dict(dt=1e-4, reset="zero"), True),
    "braille_subgraph_2023.nir": (dict(dt=1e-4, reset="zero"), True),
}
LETTERS = ("Space", "A", "E", "I", "O", "U", "Y")
RULES = ("direct", "single", "single-identified", "relayed")


def braille_inputs(reps: int, seed: int, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(N, steps, 12) merged ON/OFF events of the 7 letters, and their labels (0..6). SYNTHETIC."""
    from snncc.data.binning import record_ms
    from snncc.data.letters import label_of
    from snncc.data.sigma_delta import encode
    from snncc.data.synth import generate

    frames, labels = generate(repetitions=reps, seed=seed)
    wanted = [label_of(k) for k in LETTERS]
    keep = np.flatnonzero(np.isin(labels, wanted))
    frames, labels = frames[keep], labels[keep]
    ev = encode(frames, 1.0)
    record_s = float(record_ms(frames.shape[1])) / 1000.0
    b = np.minimum((ev.times / (record_s / steps)).astype(np.int64), steps - 1)
    x = np.zeros((frames.shape[0], steps, ev.n_taxels), np.uint8)
    x[ev.sample, b, ev.taxel] = 1
    return x, np.array([wanted.index(v) for v in labels])


def xylosim_counts(low, x) -> tuple[np.ndarray, float]:
    t0 = time.perf_counter()
    out = XyloSimOracle(XyloSpec(**low.spec)).run(low.chip_input(x)).output_spikes
    return low.read_output(out, x.shape[1]).sum(axis=1), time.perf_counter() - t0


def rockpool_counts(python: str, graph: Path, dt: float, x: np.ndarray) -> tuple[np.ndarray | None, str]:
    with tempfile.TemporaryDirectory() as tmp:
        xin, xout = Path(tmp) / "x.npz", Path(tmp) / "counts.npz"
        np.savez(xin, x=x)
        try:
            proc = subprocess.run([python, str(ROOT / "bench" / "studies" / "xylo_rockpool_flow.py"), str(graph), "--dt", str(dt),
                                   "--inputs", str(xin), "--out", str(xout)], capture_output=True, text=True)
        except OSError as err:           # no such interpreter: the row says so, the other rows still run
            return None, f"--rockpool-python {python}: {err.strerror}"
        if proc.returncode:
            return None, (proc.stderr.strip().splitlines() or ["failed"])[-1]
        data = np.load(xout, allow_pickle=False)
        return data["counts"], (f"dashes mem {sorted(set(data['dash_mem'].tolist()))} syn "
                                f"{sorted(set(data['dash_syn'].tolist()))} out mem "
                                f"{sorted(set(data['dash_mem_out'].tolist()))} syn {sorted(set(data['dash_syn_out'].tolist()))}; "
                                f"thresholds {int(data['threshold'].min())}..{int(data['threshold'].max())}")


def ceiling(ref, x, base, noise: float, draws: int = 3) -> dict:
    rows = [agreement(float_counts(perturbed(ref, noise, 100 + k), x), base) for k in range(draws)]
    return {"mean_share": float(np.mean([r.share for r in rows])),
            "count_correlation": float(np.mean([r.count_correlation for r in rows])),
            "draws": [r.as_dict() for r in rows]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=256)
    ap.add_argument("--density", type=float, default=0.08)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--braille-reps", type=int, default=100)
    ap.add_argument("--calibration", type=int, default=256)
    ap.add_argument("--rockpool-python", default="/work/venvs/rockpool/bin/python")
    ap.add_argument("--graphs", nargs="*", default=list(GRAPHS))
    ap.add_argument("--out", default=str(ROOT / "bench" / "studies" / "results" / "xylo_side_by_side.json"))
    args = ap.parse_args()

    inputs = {"random": random_inputs(args.samples, args.steps, 12, args.density, args.seed)}
    bx, blabels = braille_inputs(args.braille_reps, args.seed, args.steps)
    inputs["braille"] = bx
    result = {"settings": vars(args), "inputs": {
        "random": f"{args.samples} seeded random spike trains (density {args.density}, seed {args.seed}), {args.steps} "
                  "steps (SYNTHETIC)",
        "braille": f"{bx.shape[0]} synthetic Braille samples (generator v2, {args.braille_reps} repetitions, seed "
                   f"{args.seed}; letters {', '.join(LETTERS)}), ON+OFF events at threshold 1 merged per taxel, "
                   f"{args.steps} steps, density {bx.mean():.3f} (SYNTHETIC)"}, "graphs": {}}
    for name in args.graphs:
        path = ROOT / "tests" / "data" / "nir" / name
        load, allow = GRAPHS[name]
        entry: dict = {}
        result["graphs"][name] = entry
        try:
            graph = load_model(path, LoadOptions(**load))
        except SnnccError as err:
            entry["skipped"] = f"cannot be read: {err}"
            print(f"{name}: skipped ({err})", flush=True)
            continue
        if all(not np.any(op.weight) for _, op in graph.items() if isinstance(op, Dense)):
            entry["skipped"] = "every weight is zero (an untrained export): the float graph is silent, nothing to compare"
            print(f"{name}: skipped ({entry['skipped']})", flush=True)
            continue
        lowered = {}
        for rule in RULES + ("auto",):
            t0 = time.perf_counter()
            try:
                lowered[rule] = lower(graph, XyloOptions(rule=rule, allow_reset_change=allow,
                                                         calibration_samples=args.calibration, time_steps=args.steps),
                                      XyloStudyKnobs(density=args.density))
            except SnnccError as err:
                entry[f"snncc {rule}"] = {"refused": str(err)}
                continue
            print(f"{name}: lowered '{rule}' -> {lowered[rule].rule} in {time.perf_counter() - t0:.0f} s", flush=True)
        if not lowered:
            print(f"{name}: refused by every rule: {entry}", flush=True)
            continue
        ref = next(iter(lowered.values())).reference
        entry["reference"] = ("the float graph with reset by subtraction (deployed; trained with reset to zero)"
                              if allow else "the float graph")
        entry["auto_choice"] = lowered["auto"].rule if "auto" in lowered else None
        entry["auto_candidates"] = lowered["auto"].candidates if "auto" in lowered else None
        entry["changes"] = next(iter(lowered.values())).changes
        for kind, x in inputs.items():
            rows: dict = {}
            entry[kind] = rows
            base = float_counts(ref, x)
            if allow:
                rows["float as trained (reset to zero)"] = agreement(float_counts(graph, x), base).as_dict()
            for rule, low in lowered.items():
                counts, seconds = xylosim_counts(low, x)
                rows[f"snncc {rule}"] = dict(agreement(counts, base).as_dict(), rule=low.rule,
                                             xylosim_seconds=seconds)
            counts, how = rockpool_counts(args.rockpool_python, path, float(graph.dt), x)
            rows["rockpool"] = agreement(counts, base).as_dict() | {"spec": how} if counts is not None \
                else {"failed": how}
            rows["decays rounded"] = agreement(float_counts(rounded_decays(ref), x), base).as_dict()
            rows["noise 1 %"] = ceiling(ref, x, base, 0.01)
            rows["noise 0.3 %"] = ceiling(ref, x, base, 0.003)
            print(f"\n{name}, {kind} inputs ({result['inputs'][kind]}):", flush=True)
            for flow, r in rows.items():
                if "share" in r:
                    shown = "undefined" if r["share"] is None else f"{r['share']:.3f} [{r['low']:.3f}, {r['high']:.3f}]"
                    print(f"  {flow:28s} {shown} over {r['decided']} decided samples"
                          + (f"   [{r['rule']}]" if "rule" in r else ""), flush=True)
                elif "mean_share" in r:
                    print(f"  {flow:28s} {r['mean_share']:.3f} (mean of {len(r['draws'])} draws), count correlation "
                          f"{r['count_correlation']:.3f}", flush=True)
                else:
                    print(f"  {flow:28s} {r}", flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1, default=float))
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()
