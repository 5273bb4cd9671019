"""Bit-exact Loihi emulation of a convolutional SNN: preparation time, peak memory and emulation time.

Workload: the NIR paper's Sinabs N-MNIST CNN (``tests/data/nir/cnn_sinabs.nir``: 2 x 34 x 34 ->
4,096 -> 4,096 -> 512 -> 256 -> 10), compiled with the real CLI (``snncc compile ... --target
loihi``) and read back; its folded convolutions are large mostly-zero projections, stored and
delivered as ``SparseBlock`` synapses. Inputs: seeded Bernoulli spike frames (p = ``--density``
per pixel and step), SYNTHETIC, ``--samples`` x ``--steps``.

Figures, for this tree's kernel and (``--baseline-rev REV``) the kernel of that git revision:
  * ``prepare_s``: ``Flat(program(network))`` (what ``PreparedNetwork`` does), in a fresh process
    per kernel: ``rss_peak_MiB``, the process's peak RSS after it, and ``rss_added_MiB``, how far
    it rose above the peak already reached while reading the bundle (0: preparing needs less);
  * ``flat_MiB``: the bytes of the flattened arrays the kernel reads;
  * ``emulate_s``: ``run_flat`` on 1 thread, best and median of ``--repeat`` runs, the kernels
    interleaved in one process (the machine is shared: ratios drift less than absolute times);
  * ``identical``: the baseline's output spikes and overflow counts equal this tree's.

    python bench/speed/bench_emulator_cnn.py --baseline-rev main     # -> bench/speed/results/emulator_cnn.json
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
GRAPH = REPO / "tests" / "data" / "nir" / "cnn_sinabs.nir"


def _kernel(rev: str | None):
    if rev is None:
        from snncc.targets.loihi.emulation import flat

        return flat
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_emulator", Path(__file__).parent / "bench_emulator.py")
    bench_emulator = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench_emulator)
    return bench_emulator.load_kernel_at(rev)[0]       # that revision's kernel (Flat, run_flat)


def _rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def prepare_worker(bundle: str, rev: str | None) -> dict:
    """In a fresh process: read the bundle, then time and measure preparing it for the kernel."""
    from snncc.targets.loihi.bundle.read import read_bundle
    from snncc.targets.loihi.emulation.emulator import program

    mod = _kernel(rev)
    net = read_bundle(bundle)
    before = _rss_mib()
    t = time.perf_counter()
    flat = mod.Flat(program(net))
    prepare = time.perf_counter() - t
    arrays = sum(a.nbytes for a in vars(flat).values() if isinstance(a, np.ndarray))
    return {"prepare_s": round(prepare, 3), "rss_peak_MiB": round(_rss_mib(), 1),
            "rss_added_MiB": round(_rss_mib() - before, 1),
            "flat_MiB": round(arrays / 2**20, 2)}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--density", type=float, default=0.05)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--baseline-rev", default=None)
    ap.add_argument("--bundle", default=None, help="a compiled cnn_sinabs bundle (else compiled here)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "emulator_cnn.json"))
    args = ap.parse_args(argv)
    if args.worker:
        print(json.dumps(prepare_worker(args.bundle, args.baseline_rev)))
        return {}

    from snncc.atomic import write_text_atomic
    from snncc.targets.loihi.bundle.read import read_bundle
    from snncc.targets.loihi.emulation.emulator import program

    with tempfile.TemporaryDirectory() as tmp:
        bundle = args.bundle or str(Path(tmp) / "cnn.net")
        if args.bundle is None:
            import snncc.api as api

            api.compile(GRAPH, target="loihi", output=bundle)
        kernels = {"this": None} | ({"baseline": args.baseline_rev} if args.baseline_rev else {})
        prepare = {}
        for name, rev in kernels.items():
            cmd = [sys.executable, __file__, "--worker", "--bundle", bundle] + (["--baseline-rev", rev] if rev else [])
            env = os.environ | {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
            prepare[name] = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True,
                                                      env=env).stdout.splitlines()[-1])
        net = read_bundle(bundle)
    rng = np.random.default_rng(0)
    x = net.drive((rng.random((args.samples, args.steps, net.input_width)) < args.density).astype(np.uint8))
    prog = program(net)
    mods = {name: _kernel(rev) for name, rev in kernels.items()}
    flats = {name: mods[name].Flat(prog) for name in mods}
    times = {name: [] for name in mods}
    out = {}
    for name in mods:
        mods[name].run_flat(flats[name], x[:1], "outputs", threads=1)      # compile / load
    for r in range(args.repeat):
        for name in (list(mods) if r % 2 == 0 else list(mods)[::-1]):
            t = time.perf_counter()
            out[name] = mods[name].run_flat(flats[name], x, "outputs", threads=1)
            times[name].append(time.perf_counter() - t)
    result = {
        "workload": {"network": " -> ".join(str(int(n)) for n in prog.n), "samples": args.samples,
                     "steps": args.steps, "inputs": f"seeded Bernoulli spikes p={args.density} (SYNTHETIC)",
                     "output_spikes": int(out["this"].counts.sum())},
        "kernels": {name: {"rev": rev or "this tree", **prepare[name],
                           "emulate_s": {"best": round(min(times[name]), 4),
                                         "median": round(float(np.median(times[name])), 4)}}
                    for name, rev in kernels.items()},
        "machine": {"load_1min": os.getloadavg()[0], "note": "shared machine: wall times are noisy"},
    }
    if "baseline" in out:
        result["identical"] = bool(np.array_equal(out["this"].output_spikes, out["baseline"].output_spikes)
                                   and out["this"].overflow == out["baseline"].overflow)
    write_text_atomic(args.out, json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
