"""Argmax agreement of a snnTorch-style NIR graph on Loihi (bit-exact emulation) vs the float IR.

The Braille-sized recurrent graph of the NIR project (12 -> 38 recurrent CubaLIF -> 7, built with
the ``nir`` package the way snnTorch exports it: dt = 1e-4, r = tau_mem/dt, w_in = tau_syn/dt)
is written to a .nir file, compiled with the real CLI (``snncc compile g.nir --target loihi -o
g.net --scale RULE``), the bundle read back and emulated bit-exactly; its output-count argmax is
compared with the IR reference simulation of the same .nir file. SYNTHETIC: random weights
(one alpha/beta/threshold per layer, no biases -- the Loihi lowering refuses Dense biases today)
and random sparse input spikes, not Braille recordings.

    python bench/nir_loihi_agreement.py [--samples 200] [--steps 100] [--seeds 0 1 2] [--json]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "nir"))

import nir  # noqa: E402
import torch  # noqa: E402

from nir_graphs import BrailleRSNN, sparse_inputs  # noqa: E402
from snncc.cli.main import run  # noqa: E402
from snncc.frontends import load_model  # noqa: E402
from snncc.ir.simulate import simulate  # noqa: E402
from snncc.targets.loihi.bundle import read_bundle  # noqa: E402
from snncc.targets.loihi.emulator import emulate  # noqa: E402
from snncc.targets.loihi.validation import pad  # noqa: E402

RULES = ("global", "per-layer", "auto")


def measure(seed: int, outliers: bool, samples: int, steps: int, workdir: Path) -> list[dict]:
    rng = np.random.default_rng(seed)
    model = BrailleRSNN.random(rng, bias=False, scale=0.3, per_neuron=False, outliers=outliers, rec_std=0.4)
    src = workdir / f"g{seed}{'o' if outliers else ''}.nir"
    nir.write(str(src), model.to_nir())
    x = sparse_inputs(rng, batch=samples, steps=steps, p=0.05).astype(np.uint8)
    ref = simulate(load_model(src), x, record="spikes")
    counts = ref.readout.numpy()
    top2 = np.sort(counts, axis=1)[:, -2:]
    # how fragile the float model itself is: 1 % multiplicative weight noise (8-bit rounding is ~1 %)
    noisy = load_model(src)
    noise = np.random.default_rng(9)
    for name in ("fc1", "fc2", "lif1.w_rec"):
        noisy.node(name).weight = noisy.node(name).weight * (1 + 0.01 * noise.standard_normal(noisy.node(name).weight.shape))
    ceiling = float(np.mean(simulate(noisy, x).prediction.numpy() == ref.prediction.numpy()))
    rows = []
    for rule in RULES:
        net_path = workdir / f"{src.stem}_{rule}.net"
        with contextlib.redirect_stdout(io.StringIO()):  # the compile report; only the figures are printed
            code = run(["compile", str(src), "--target", "loihi", "-o", str(net_path), "--scale", rule, "--json"])
        if code != 0:
            rows.append({"seed": seed, "outliers": outliers, "rule": rule, "error": f"compile exit {code}"})
            continue
        net = read_bundle(net_path)
        res = emulate(net, pad(x, int(net.metadata.get("output_shift", 0))))
        rows.append({
            "seed": seed, "outliers": outliers, "rule": rule,
            "argmax_agreement": float(np.mean(res.prediction == ref.prediction.numpy())),
            "count_mean_abs_error": float(np.mean(np.abs(res.counts - counts))),
            "hidden_rate": float(ref.spikes["lif1.lif"].mean()),
            "float_margin_le_2": float(np.mean(top2[:, 1] - top2[:, 0] <= 2)),
            "float_vs_float_with_1pct_weight_noise": ceiling,
        })
    return rows


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    torch.set_num_threads(1)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for outliers in (False, True):
            for seed in args.seeds:
                rows += measure(seed, outliers, args.samples, args.steps, Path(tmp))
    summary = {}
    for outliers in (False, True):
        for rule in RULES:
            vals = [r["argmax_agreement"] for r in rows if r["outliers"] == outliers and r["rule"] == rule
                    and "argmax_agreement" in r]
            summary[f"{'outliers' if outliers else 'plain'}/{rule}"] = float(np.mean(vals)) if vals else None
    record = {"samples": args.samples, "steps": args.steps, "seeds": args.seeds,
              "data": "synthetic: random sparse spikes (p=0.05), random snnTorch-style weights",
              "mean_argmax_agreement": summary,
              "mean_float_1pct_noise_agreement": {
                  k: float(np.mean([r["float_vs_float_with_1pct_weight_noise"] for r in rows
                                    if r["outliers"] == (k == "outliers") and "argmax_agreement" in r]))
                  for k in ("plain", "outliers")},
              "rows": rows}
    if args.json:
        print(json.dumps(record, indent=2))
    else:
        print("\n".join(f"{k}: {v:.3f}" for k, v in summary.items()))
        print("float model vs itself with 1% weight noise:", record["mean_float_1pct_noise_agreement"])
    return record


if __name__ == "__main__":
    main()
