"""Argmax agreement of a snnTorch-style NIR graph on Loihi (bit-exact emulation) vs the float IR.

The Braille-sized recurrent graph of the NIR project (12 -> 38 recurrent CubaLIF -> 7, built with
the ``nir`` package the way snnTorch exports it: dt = 1e-4, r = tau_mem/dt, w_in = tau_syn/dt)
is written to a .nir file, compiled with the real CLI (``snncc compile g.nir --target loihi -o
g.net --scale RULE``), the bundle read back and emulated bit-exactly; its output-count argmax is
compared with the IR reference simulation of the same .nir file. Random-weight cases: plain
weights, recurrent outliers (a few weights 100x the median |w|), Affine biases, and both. Trained
cases: the same graph with biases trained in snnTorch's step order to tell 7 random rate patterns
apart (``tests/nir/nir_graphs.py``), and that graph with 7 recurrent outliers (100x the median
|w|) fine-tuned around; inputs are fresh random sparse spike trains drawn from the patterns.
SYNTHETIC throughout: random or pattern-trained weights and random spikes, not Braille recordings.

How to read the agreement (a random graph is not a trained one):
    ceiling   the float model against itself with 1 % multiplicative weight noise (8-bit rounding is
              of that order): what any 8-bit deployment can hope for on these inputs
    margin>=2 agreement on the samples whose float top-2 output counts differ by >= 2 spikes
              (exact ties and 1-spike margins flip under any perturbation)
    majority  the share of the most frequent float prediction (a constant predictor's agreement)
Regime (--regime): "weak" (default: weights x0.1, recurrent std 0.1, input p 0.1, hidden rate ~7 %)
or "chaotic" (x0.3, 0.4, 0.05, hidden rate ~35 %: 1 % weight noise alone flips 5-12 % of outputs).

    python bench/studies/nir_loihi_agreement.py [--samples 200] [--steps 100] [--seeds 0 1 2] [--regime weak]
                                        [--no-trained] [--json]

Real trained graphs (``--real``): the NIR paper's Braille RSNNs in tests/data/nir (braille_zero_2023:
reset to zero; braille_noDelay_noBias_subtract: compiled with --reset subtract --allow-reset-change
and compared with the same graph with reset to zero in float), compiled per rule with the CLI, the
bundle read back and emulated; argmax agreement and output-count correlation (Pearson over samples
x classes) against the float graph on seeded random spike trains, with the float graph's own
agreement under 1 % and 0.3 % multiplicative weight noise beside them (mean over 3 noise draws):

    python bench/studies/nir_loihi_agreement.py --real [--samples 40] [--steps 256] [--density 0.08] [--input-seed 0] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "nir"))

import nir  # noqa: E402
import torch  # noqa: E402

from nir_graphs import BrailleRSNN, pattern_inputs, sparse_inputs, trained_braille_rsnn  # noqa: E402
import snncc.api  # noqa: E402
from snncc.errors import SnnccError  # noqa: E402
from snncc.frontends import load_model  # noqa: E402
from snncc.ir.nodes import Input  # noqa: E402
from snncc.ir.simulate import simulate  # noqa: E402
from snncc.targets.loihi.bundle.read import read_bundle  # noqa: E402
from snncc.targets.loihi.emulation.emulator import emulate  # noqa: E402
from snncc.targets.loihi.checks.exactness import pad  # noqa: E402

RULES = ("global", "per-layer", "split", "fine", "auto")
REAL = {"braille_zero_2023.nir": {}, "braille_noDelay_noBias_subtract.nir": {"reset": "subtract",
                                                                            "allow_reset_change": True}}
REAL_DIR = Path(__file__).resolve().parents[2] / "tests" / "data" / "nir"
NOISE_LEVELS = (0.01, 0.003)
CASES = {"plain": (False, False), "outliers": (True, False), "bias": (False, True), "bias+outliers": (True, True)}
TRAINED = ("trained", "trained+outliers")
REGIMES = {"weak": dict(scale=0.1, rec_std=0.1, p=0.1), "chaotic": dict(scale=0.3, rec_std=0.4, p=0.05)}
REC_NAME = "lif1.w_rec"


def float_ceiling(src: Path, x: np.ndarray, reference: np.ndarray) -> float:
    """Agreement of the float model with itself under 1 % multiplicative weight noise."""
    noisy = load_model(src)
    noise = np.random.default_rng(9)
    for name in ("fc1", "fc2", REC_NAME):
        w = noisy.node(name).weight
        noisy.node(name).weight = w * (1 + 0.01 * noise.standard_normal(w.shape))
    return float(np.mean(np.asarray(simulate(noisy, x).prediction) == reference))


def random_case(seed: int, case: str, regime: dict, samples: int, steps: int):
    """(model, inputs, labels or None) of a random-weight case."""
    outliers, bias = CASES[case]
    rng = np.random.default_rng(seed)
    model = BrailleRSNN.random(rng, bias=bias, scale=regime["scale"], per_neuron=False, outliers=outliers,
                               rec_std=regime["rec_std"])
    return model, sparse_inputs(rng, batch=samples, steps=steps, p=regime["p"]).astype(np.uint8), None


def trained_case(seed: int, case: str, samples: int, steps: int):
    """(model, inputs, labels) of a trained case: fresh pattern inputs, not those it was trained on."""
    model, patterns = trained_braille_rsnn(seed, outliers=case.endswith("outliers"), steps=steps)
    x, labels = pattern_inputs(np.random.default_rng(1000 + seed), patterns, samples, steps)
    return model, x.astype(np.uint8), labels


def compile_exit(src: Path, out: Path, **options) -> int:
    """``snncc.api.compile`` for Loihi; the exit status ``snncc compile`` would give (0, 2 refused, 1 a bug)."""
    try:
        snncc.api.compile(src, target="loihi", output=out, **options)
    except SnnccError:
        return 2
    except Exception:
        return 1
    return 0


def measure(seed: int, case: str, model: BrailleRSNN, x: np.ndarray, labels, workdir: Path) -> list[dict]:
    src = workdir / f"g{seed}_{case.replace('+', '_')}.nir"
    nir.write(str(src), model.to_nir())
    ref = simulate(load_model(src), x, record="spikes")
    counts = np.asarray(ref.readout)
    pred = np.asarray(ref.prediction)
    top2 = np.sort(counts, axis=1)[:, -2:]
    firm = (top2[:, 1] - top2[:, 0]) >= 2
    rec = model.w_rec
    common = {"seed": seed, "case": case, "hidden_rate": float(ref.spikes["lif1.lif"].mean()),
              "float_ceiling": float_ceiling(src, x, pred), "majority": float(np.bincount(pred).max() / pred.size),
              "margin_ge_2_share": float(firm.mean()),
              "rec_max_over_median": float(np.max(np.abs(rec)) / np.median(np.abs(rec)))}
    if labels is not None:
        common["float_accuracy"] = float(np.mean(pred == labels))
    rows = []
    for rule in RULES:
        net_path = workdir / f"{src.stem}_{rule}.net"
        code = compile_exit(src, net_path, scale=rule)
        if code != 0:
            rows.append({**common, "rule": rule, "error": f"compile exit {code}"})
            continue
        net = read_bundle(net_path)
        res = emulate(net, pad(x, int(net.metadata.get("output_shift", 0))))
        same = res.prediction == pred
        row = {**common, "rule": rule, "chosen": net.metadata.get("quantization", {}).get("reason", ""),
               "argmax_agreement": float(same.mean()),
               "agreement_margin_ge_2": float(same[firm].mean()) if firm.any() else None}
        if labels is not None:
            row["loihi_accuracy"] = float(np.mean(res.prediction == labels))
        rows.append(row)
    return rows


def real_graphs(samples: int, steps: int, density: float, workdir: Path, seed: int = 0) -> dict:
    """Per real graph and rule: argmax agreement and count correlation of the emulated bundle with the float graph."""
    from snncc.frontends import LoadOptions
    from snncc.targets.kit.agreement import count_correlation, random_inputs
    from snncc.targets.kit.reference import perturbed

    out = {}
    for name, extra in REAL.items():
        src = REAL_DIR / name
        reset = "zero" if extra else None      # the float reference: the same graph with reset to zero
        graph = load_model(src, LoadOptions(dt=1e-4, reset=reset))
        x = random_inputs(samples, steps, graph.node(graph.of_kind(Input)[0]).width, density, seed)
        ref = simulate(graph, x, record="spikes")
        c_ref, p_ref = np.asarray(ref.readout), np.asarray(ref.prediction)
        entry = {"ceiling": {}, "rules": {}}
        for noise in NOISE_LEVELS:
            runs = [simulate(perturbed(graph, noise, seed), x) for seed in (9, 10, 11)]
            entry["ceiling"][f"noise {100 * noise:g} %"] = {
                "argmax_agreement": float(np.mean([np.mean(np.asarray(r.prediction) == p_ref) for r in runs])),
                "count_correlation": float(np.mean([count_correlation(np.asarray(r.readout), c_ref) for r in runs]))}
        for rule in RULES:
            net_path = workdir / f"{src.stem}_{rule}.net"
            code = compile_exit(src, net_path, dt=1e-4, scale=rule, **extra)
            if code != 0:
                entry["rules"][rule] = {"error": f"compile exit {code}"}
                continue
            net = read_bundle(net_path)
            shift = int(net.metadata.get("output_shift", 0))
            res = emulate(net, pad(x, shift))
            counts = res.output_spikes[:, shift:shift + steps].sum(axis=1)
            q = net.metadata.get("quantization", {})
            entry["rules"][rule] = {
                "argmax_agreement": float(np.mean(np.argmax(counts, axis=1) == p_ref)),
                "count_correlation": count_correlation(counts, c_ref),
                "chosen": q.get("rule"), "candidates": (q.get("calibration") or {}).get("errors", {})}
        out[name] = entry
    return out


def _mean(rows: list[dict], key: str) -> float | None:
    vals = [r[key] for r in rows if r.get(key) is not None]
    return float(np.mean(vals)) if vals else None


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--regime", choices=sorted(REGIMES), default="weak")
    ap.add_argument("--no-trained", action="store_true", help="skip the trained cases (about 50 s of training per seed)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--real", action="store_true", help="the NIR paper's trained Braille graphs (tests/data/nir)")
    ap.add_argument("--density", type=float, default=0.08, help="--real: spike density of the random inputs")
    ap.add_argument("--input-seed", type=int, default=0, help="--real: seed of the random inputs")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)
    if args.real:
        with tempfile.TemporaryDirectory() as tmp:
            real = real_graphs(args.samples, args.steps, args.density, Path(tmp), args.input_seed)
        record = {"samples": args.samples, "steps": args.steps, "density": args.density, "input_seed": args.input_seed,
                  "data": "SYNTHETIC inputs: seeded random spike trains; trained weights of the NIR paper", "graphs": real}
        if args.json:
            print(json.dumps(record, indent=2))
        else:
            print(f"{args.samples} random spike trains x {args.steps} steps, density {args.density}; "
                  "argmax agreement / count correlation with the float graph")
            for name, e in real.items():
                print(name + "   ceiling: " + ", ".join(f"{k} {v['argmax_agreement']:.3f}/{v['count_correlation']:.4f}"
                                                         for k, v in e["ceiling"].items()))
                for rule, r in e["rules"].items():
                    print(f"  {rule:10s} " + (r["error"] if "error" in r else
                                              f"{r['argmax_agreement']:.3f} / {r['count_correlation']:.4f}"
                                              + (f"  (chose {r['chosen']})" if rule == "auto" else "")))
        return record
    regime = REGIMES[args.regime]
    cases = list(CASES) + ([] if args.no_trained else list(TRAINED))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in cases:
            for seed in args.seeds:
                if case in CASES:
                    model, x, labels = random_case(seed, case, regime, args.samples, args.steps)
                else:
                    model, x, labels = trained_case(seed, case, args.samples, args.steps)
                rows += measure(seed, case, model, x, labels, Path(tmp))
    summary = {}
    for case in cases:
        mine = [r for r in rows if r["case"] == case]
        summary[case] = {
            key: _mean(mine, key) for key in ("float_ceiling", "majority", "hidden_rate", "margin_ge_2_share",
                                              "rec_max_over_median", "float_accuracy")}
        summary[case].update({
            rule: {"all": _mean([r for r in mine if r["rule"] == rule], "argmax_agreement"),
                   "margin_ge_2": _mean([r for r in mine if r["rule"] == rule], "agreement_margin_ge_2"),
                   "loihi_accuracy": _mean([r for r in mine if r["rule"] == rule], "loihi_accuracy")}
            for rule in RULES})
    record = {"samples": args.samples, "steps": args.steps, "seeds": args.seeds, "regime": {args.regime: regime},
              "data": "SYNTHETIC: random sparse spikes; random or pattern-trained snnTorch-style weights",
              "summary": summary, "rows": rows}
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print(f"regime {args.regime} {regime}; mean over seeds {args.seeds}; agreement all samples / margin >= 2")
        for case, s in summary.items():
            acc = f"  float accuracy {s['float_accuracy']:.3f}" if s["float_accuracy"] is not None else ""
            print(f"{case:16s} ceiling {s['float_ceiling']:.3f}  majority {s['majority']:.3f}{acc}  " + "  ".join(
                f"{rule} {s[rule]['all']:.3f}/{s[rule]['margin_ge_2']:.3f}" for rule in RULES))
    return record


if __name__ == "__main__":
    main()
