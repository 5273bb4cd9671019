"""The NIR paper's Sinabs N-MNIST CNN (``cnn_sinabs.nir``: Conv2d, IF, SumPool2d, Flatten, Affine) on
both targets, against its float IR.

Both artefacts are built with the real CLI (``snncc compile cnn_sinabs.nir --target loihi -o
cnn.net --time-steps T`` and ``--target jetson -o dir --time-steps T``). Inputs: seeded random
spike frames shaped like N-MNIST (2 x 34 x 34 per step, Bernoulli with probability p per pixel
and step) -- SYNTHETIC, not N-MNIST recordings, so the network's outputs are not digit decisions.

Loihi: the bundle read back and emulated bit-exactly, against the IR reference of the .nir file:
per-layer spike agreement, argmax agreement of the output counts, their correlation. Beside it the
float graph against itself with 0.1 % and 1 % multiplicative weight noise (8-bit weights are of
that order): the ceiling any 8-bit deployment can reach on these inputs. Jetson: the ONNX model in
ONNX Runtime against the IR (output spikes, argmax).

    python bench/studies/cnn_sinabs_agreement.py [--samples 32] [--steps 100] [--density 0.01 0.05] [--json]
"""

from __future__ import annotations

import argparse
import json
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DEFAULT_GRAPH = ROOT / "tests" / "data" / "nir" / "cnn_sinabs.nir"


def _frames(batch, steps, p, seed):
    return (np.random.default_rng(seed).random((batch, steps, 2312)) < p).astype(np.uint8)


def _agreement(got: dict, want: dict, names: list[str]) -> dict:
    last = names[-1]
    c_got, c_want = got[last].sum(axis=1), want[last].sum(axis=1)
    corr = float(np.corrcoef(c_got.ravel(), c_want.ravel())[0, 1]) if c_want.std() > 0 else float("nan")
    return {"spike_agreement": {n: round(float(np.mean(got[n] == want[n])), 5) for n in names},
            "argmax_agreement": float(np.mean(c_got.argmax(axis=1) == c_want.argmax(axis=1))),
            "count_correlation": round(corr, 4)}


def _noisy(graph, level, seed):
    from snncc.ir.nodes import Conv, Dense

    g = graph.copy()
    rng = np.random.default_rng(seed)
    for _, op in g.items():
        pooling = isinstance(op, Conv) and op.weight.shape[1] == 1 and op.groups == op.in_shape[0]
        if isinstance(op, (Conv, Dense)) and not pooling:
            op.weight = op.weight * (1 + level * rng.standard_normal(op.weight.shape))
    return g


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--graph", type=Path, default=DEFAULT_GRAPH)
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--density", type=float, nargs="+", default=[0.01, 0.05])
    ap.add_argument("--scale", default="auto")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    import onnxruntime as ort

    import snncc.api as api
    from snncc.frontends import LoadOptions, load_model
    from snncc.ir.nodes import LIF
    from snncc.ir.simulate import simulate
    from snncc.targets.loihi.bundle.read import read_bundle
    from snncc.targets.loihi.emulation.emulator import PreparedNetwork
    from snncc.targets.loihi.checks.exactness import pad

    graph = load_model(args.graph, LoadOptions())
    names = graph.of_kind(LIF)
    out: dict = {"graph": str(args.graph), "samples": args.samples, "steps": args.steps, "scale": args.scale,
                 "inputs": "SYNTHETIC: seeded Bernoulli spike frames 2x34x34 (N-MNIST-shaped), not N-MNIST",
                 "load_1min": __import__("os").getloadavg()[0], "results": []}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        timings = {}
        for target, dest in (("loihi", tmp / "cnn.net"), ("jetson", tmp / "jet")):
            t0 = time.perf_counter()
            api.compile(args.graph, target=target, output=dest, time_steps=args.steps,
                        scale=args.scale if target == "loihi" else None)
            timings[target] = round(time.perf_counter() - t0, 1)
        out["compile_seconds"] = timings
        net = read_bundle(tmp / "cnn.net")
        t0 = time.perf_counter()
        prepared = PreparedNetwork(net)
        out["emulator_prepare_seconds"] = round(time.perf_counter() - t0, 2)
        session = ort.InferenceSession(str(tmp / "jet" / "model.onnx"), providers=["CPUExecutionProvider"])
        shifts = net.metadata.get("population_shifts") or {}
        lead = max([int(net.metadata.get("output_shift", 0))] + [int(v) for v in shifts.values()])
        for k, p in enumerate(args.density):
            x = _frames(args.samples, args.steps, p, args.seed + k)
            ref = simulate(graph, x, record="spikes")
            want = {n: np.asarray(ref.spikes[n]).astype(np.uint8) for n in names}
            t0 = time.perf_counter()
            res = prepared.run(pad(x, lead), record="all")
            emu_s = time.perf_counter() - t0
            got = {n: res.spikes[i][:, shifts.get(n, 0):shifts.get(n, 0) + args.steps, :graph.node(n).n]
                   for i, n in enumerate(names, start=1)}
            row = {"density": p, "mean_rates": {n: round(float(want[n].mean()), 4) for n in names},
                   "loihi": _agreement(got, want, names), "emulator_seconds": round(emu_s, 2),
                   "loihi_overflow": res.overflow}
            for level in (0.001, 0.01):
                noisy = simulate(_noisy(graph, level, 7), x, record="spikes")
                row[f"float_noise_{level:g}"] = _agreement(
                    {n: np.asarray(noisy.spikes[n]).astype(np.uint8) for n in names}, want, names)
            counts, spikes = session.run(["counts", "output_spikes"], {"events": x.astype(np.float32)})
            last = want[names[-1]]
            row["jetson"] = {"output_spikes_equal": float(np.mean(spikes == last)),
                             "argmax_agreement": float(np.mean(counts.argmax(axis=1) == last.sum(axis=1).argmax(axis=1)))}
            out["results"].append(row)
    out["max_rss_mb"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)
    if args.json:
        print(json.dumps(out, indent=1))
        return 0
    print(f"{out['graph']}: {args.samples} samples x {args.steps} steps, scale {args.scale}; {out['inputs']}")
    print(f"compile seconds {timings}, emulator prepare {out['emulator_prepare_seconds']} s, "
          f"peak RSS {out['max_rss_mb']} MB, load {out['load_1min']:.1f}")
    for row in out["results"]:
        lo = row["loihi"]
        print(f"p={row['density']}: rates {row['mean_rates']}")
        print(f"  Loihi emulator vs float IR: argmax {lo['argmax_agreement']:.3f}, count corr "
              f"{lo['count_correlation']:.3f}, spikes {lo['spike_agreement']} ({row['emulator_seconds']} s)")
        for level in ("0.001", "0.01"):
            r = row[f"float_noise_{level}"]
            print(f"  ceiling: float with {float(level) * 100:g} % weight noise: argmax {r['argmax_agreement']:.3f}, "
                  f"count corr {r['count_correlation']:.3f}")
        print(f"  Jetson ONNX (ORT) vs float IR: output spikes equal {row['jetson']['output_spikes_equal']:.4f}, "
              f"argmax {row['jetson']['argmax_agreement']:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
