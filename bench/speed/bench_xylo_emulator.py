"""snncc's bit-exact Xylo emulator vs SynSense's XyloSim (xylosim 0.1.3), side by side in one run.

Two networks, each run on the same seeded inputs by both:

* ``braille``: the size of the NIR paper's Braille graph, 12 -> 40 (recurrent) -> 7, 256 steps:
  the weights of ``tests/data/nir/braille_noDelay_noBias_subtract.nir`` (dt 1e-4) scaled to int8
  with one global factor per layer the way Rockpool's ``global_quantize`` does (their gain onto V
  per step folded in), thresholds scaled alike, dashes round(log2(tau / dt)). A timing workload
  with the trained graph's activity, NOT snncc's lowering of it (that is the lowering's job);
* ``large``: Xylo Audio 2 at its limits, 16 -> 1000 -> 8 with two synapses, each hidden neuron
  with 64 random recurrent targets (the chip's fan-out), every hidden neuron reached by the inputs
  and feeding the outputs; SYNTHETIC zero-mean weights, thresholds set so that about 5 % of the
  hidden neurons fire per step;
* ``replicated``: spec.npz of ``snncc compile braille_noDelay_noBias_subtract.nir --dt 1e-4 --reset subtract
  --target xylo --replicas 4 --relays both`` (12 -> 576 -> 7: four copies of the relayed network, each a block
  of the recurrent matrix), compiled here unless ``--replicated DIR`` names such an artefact (not with
  ``--quick``).

Inputs: Bernoulli spikes, p = 0.08 per channel and step (SYNTHETIC), seeded.

Figures (wall time, best of ``--repeat``, and CPU time where one thread runs; XyloSim and snncc's 1-thread run
alternate, repeat by repeat, so that the machine's load weighs on both alike):
  * XyloSim: one ``xylosim.v2.XyloLayer`` built once (its build time reported apart), then per
    sample ``reset_all()`` and ``evolve(raster)`` -- recording off in Rockpool's sense (only the
    output is taken; the C++ records internally regardless); per-sample time over
    ``--xylosim-samples`` samples;
  * snncc: the network prepared once (``emulation.kernel.prepare``, time reported apart), then
    ``run_prepared`` at batch 1 and at batch ``--batch`` (1,024) on 1 thread and on all cores;
    per-sample time; also ``emulate()`` end to end (input checks and preparation included);
  * ``identical``: snncc's output spikes equal XyloSim's on the samples XyloSim ran;
  * ``ratio_*``: XyloSim's time per sample over snncc's (the goal: >= 20 at batch 1,024).

Other work shares the machine: ``machine`` records the load before and after and the cores; a
load above the core count inflates wall times (CPU times and the ratios in one run drift less).

    python bench/speed/bench_xylo_emulator.py                     # -> bench/speed/results/xylo_emulator.json
    python bench/speed/bench_xylo_emulator.py --quick             # smaller batch and fewer repeats
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))          # tests.xylo.oracle: the xylosim driver the tests use

from snncc.targets.xylo.emulation.kernel import prepare, run_prepared   # noqa: E402
from snncc.targets.xylo.emulation.emulator import emulate      # noqa: E402
from snncc.targets.xylo.spec import XyloSpec                  # noqa: E402
from tests.xylo.oracle import XyloSimOracle                   # noqa: E402

BRAILLE_NIR = REPO / "tests" / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
STEPS = 256
DENSITY = 0.08


def braille_spec(dt: float = 1e-4) -> XyloSpec:
    """The Braille graph's weights on Xylo's integer scale (a timing workload; see the docstring)."""
    import nir

    nodes = nir.read(str(BRAILLE_NIR)).nodes
    hidden, output = nodes["lif1.lif"], nodes["lif2"]

    def gain(lif):   # one input unit's effect on V after a step: (dt / tau_syn) w_in (dt / tau_mem) r
        return dt / lif.tau_syn * lif.w_in * dt / lif.tau_mem * lif.r

    w_in = nodes["fc1"].weight.T * gain(hidden)
    w_rec = nodes["lif1.w_rec"].weight.T * gain(hidden)
    w_out = nodes["fc2"].weight.T * gain(output)
    scale_h = 127 / max(np.abs(w_in).max(), np.abs(w_rec).max())
    scale_o = 127 / np.abs(w_out).max()
    n, n_out = w_rec.shape[0], w_out.shape[1]
    dash = lambda tau: np.clip(np.round(np.log2(tau / dt)), 0, 15).astype(int)   # noqa: E731
    return XyloSpec(
        weights_in=np.round(w_in * scale_h).astype(int), weights_rec=np.round(w_rec * scale_h).astype(int),
        weights_out=np.round(w_out * scale_o).astype(int),
        dash_mem=dash(hidden.tau_mem), dash_syn=dash(hidden.tau_syn), dash_syn_2=dash(hidden.tau_syn),
        dash_mem_out=dash(output.tau_mem), dash_syn_out=dash(output.tau_syn),
        threshold=np.round(hidden.v_threshold * scale_h).astype(int),
        threshold_out=np.round(output.v_threshold * scale_o).astype(int),
        bias=np.zeros(n, int), bias_out=np.zeros(n_out, int), weight_shift_in=0, weight_shift_rec=0,
        weight_shift_out=0, aliases=[[] for _ in range(n)], dt=dt)


def large_spec(seed: int = 0) -> XyloSpec:
    """16 -> 1000 -> 8, two synapses, 64 recurrent targets per hidden neuron (SYNTHETIC; zero-mean
    weights, thresholds chosen so that about 5 % of the hidden neurons fire per step)."""
    rng = np.random.default_rng(seed)
    n_in, n, n_out, fanout = 16, 1000, 8, 64
    w_rec = np.zeros((n, n, 2), int)
    for j in range(n):
        w_rec[j, rng.choice(n, fanout, replace=False)] = rng.integers(-128, 128, (fanout, 2))
    return XyloSpec(
        weights_in=rng.integers(-128, 128, (n_in, n, 2)), weights_rec=w_rec, weights_out=rng.integers(-128, 128, (n, n_out)),
        dash_mem=rng.integers(1, 4, n), dash_syn=rng.integers(1, 3, n), dash_syn_2=rng.integers(1, 3, n),
        dash_mem_out=np.full(n_out, 3), dash_syn_out=np.full(n_out, 2),
        threshold=rng.integers(8000, 16000, n), threshold_out=np.full(n_out, 8000),
        bias=np.zeros(n, int), bias_out=np.zeros(n_out, int), weight_shift_in=5, weight_shift_rec=2,
        weight_shift_out=2, aliases=[[] for _ in range(n)], dt=1e-3)


def replicated_spec() -> XyloSpec:
    """The spec.npz of the Braille graph compiled with ``--replicas 4 --relays both`` (about a minute)."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="snncc-xylo-bench-") as tmp:
        out = Path(tmp) / "replicated.xylo"
        subprocess.run([sys.executable, "-m", "snncc.cli.main", "compile", str(BRAILLE_NIR), "--dt", "1e-4", "--reset",
                        "subtract", "--target", "xylo", "--replicas", "4", "--relays", "both", "-o", str(out)],
                       check=True, stdout=subprocess.DEVNULL)
        return XyloSpec.load_npz(out / "spec.npz")


def best_of(repeat: int, fn) -> tuple[float, float]:
    """(best wall seconds, best CPU seconds of this process) over ``repeat`` calls of ``fn``."""
    walls, cpus = [], []
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return min(walls), min(cpus)


def measure(name: str, spec: XyloSpec, batch: int, xylosim_samples: int, repeat: int, threads: int) -> dict:
    rng = np.random.default_rng(1)
    x = (rng.random((batch, STEPS, spec.n_in)) < DENSITY).astype(np.uint8)
    x_sim = x[:xylosim_samples]

    t0 = time.perf_counter()
    oracle = XyloSimOracle(spec)
    build_s = time.perf_counter() - t0
    sim_out = np.stack([oracle.run_one(s) for s in x_sim])   # warm-up, and the outputs to compare

    t0 = time.perf_counter()
    prepared = prepare(spec)
    prepare_s = time.perf_counter() - t0
    run_prepared(prepared, x[:2], threads=1)                  # compiled (or loaded from numba's cache)
    identical = bool(np.array_equal(run_prepared(prepared, x_sim, threads=1).output_spikes, sim_out))
    # XyloSim and snncc on 1 thread alternate, so that the machine's load weighs on both alike
    sims, ones = [], []
    for _ in range(repeat):
        sims.append(best_of(1, lambda: [oracle.run_one(s) for s in x_sim]))
        ones.append(best_of(1, lambda: run_prepared(prepared, x, threads=1)))
    sim_wall, sim_cpu = min(w for w, _ in sims), min(c for _, c in sims)
    one_wall, one_cpu = min(w for w, _ in ones), min(c for _, c in ones)
    b1_wall, b1_cpu = best_of(max(repeat, 5), lambda: run_prepared(prepared, x[:1], threads=1))
    all_wall, _ = best_of(repeat, lambda: run_prepared(prepared, x, threads=threads))
    api_wall, _ = best_of(repeat, lambda: emulate(spec, x, threads=threads))
    rec = emulate(spec, x[:64], record=True)

    per = lambda seconds, samples: seconds / samples * 1e6   # noqa: E731  (microseconds per sample)
    sim_us = per(sim_wall, len(x_sim))
    record = {
        "network": {"n_in": spec.n_in, "n_hidden": spec.n_hidden, "n_out": spec.n_out,
                    "synapses_used": spec.synapses_used, "max_fanout": int(spec.fanout().max()), "steps": STEPS,
                    "input_density": DENSITY},
        "activity": {"hidden_events_per_neuron_step": float(rec.spikes.mean()),
                     "hidden_active_fraction_per_step": float((rec.spikes > 0).mean()),
                     "output_events_per_neuron_step": float(rec.output_spikes.mean())},
        "identical_to_xylosim": identical,
        "xylosim": {"build_s": build_s, "samples": len(x_sim), "us_per_sample_wall": sim_us,
                    "us_per_sample_cpu": per(sim_cpu, len(x_sim))},
        "snncc": {"prepare_s": prepare_s, "batch": batch, "threads": threads,
                  "batch1_us_wall": per(b1_wall, 1), "batch1_us_cpu": per(b1_cpu, 1),
                  "us_per_sample_1_thread_wall": per(one_wall, batch), "us_per_sample_1_thread_cpu": per(one_cpu, batch),
                  "us_per_sample_all_threads_wall": per(all_wall, batch),
                  "emulate_api_us_per_sample_all_threads_wall": per(api_wall, batch)},
    }
    s = record["snncc"]
    record["ratio_xylosim_over_snncc"] = {
        f"batch{batch}_1_thread": sim_us / s["us_per_sample_1_thread_wall"],
        f"batch{batch}_1_thread_cpu": record["xylosim"]["us_per_sample_cpu"] / s["us_per_sample_1_thread_cpu"],
        f"batch{batch}_{threads}_threads": sim_us / s["us_per_sample_all_threads_wall"],
        "batch1": sim_us / s["batch1_us_wall"],
    }
    print(f"{name}: xylosim {sim_us:.0f} us/sample; snncc batch {batch} {s['us_per_sample_1_thread_wall']:.1f} "
          f"us/sample (1 thread), {s['us_per_sample_all_threads_wall']:.1f} ({threads} threads), batch 1 "
          f"{s['batch1_us_wall']:.1f} us; ratios " + ", ".join(f"{k} {v:.1f}x" for k, v in
                                                            record["ratio_xylosim_over_snncc"].items())
          + f"; identical {identical}", flush=True)
    return record


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=1024)
    ap.add_argument("--xylosim-samples", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--quick", action="store_true", help="batch 256, 16 XyloSim samples, 2 repeats")
    ap.add_argument("--replicated", default=None, help="an artefact of --replicas 4 --relays both (default: compiled)")
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "speed" / "results" / "xylo_emulator.json")
    args = ap.parse_args(argv)
    if args.quick:
        args.batch, args.xylosim_samples, args.repeat = 256, 16, 2
    load_before = os.getloadavg()[0]
    uptime_before = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    result = {
        "what": "snncc Xylo emulator vs XyloSim (xylosim 0.1.3), per sample, same inputs, one process",
        "goal": "at batch 1,024, >= 20x XyloSim's time per sample (XyloSim built once, recording off)",
        "workloads": {},
    }
    workloads = [("braille", braille_spec()), ("large", large_spec())]
    if args.replicated is not None:
        workloads.append(("replicated", XyloSpec.load_npz(Path(args.replicated) / "spec.npz")))
    elif not args.quick:
        workloads.append(("replicated", replicated_spec()))
    for name, spec in workloads:
        result["workloads"][name] = measure(name, spec, args.batch, args.xylosim_samples, args.repeat, args.threads)
    result["machine"] = {"cores": os.cpu_count(), "platform": platform.platform(), "processor": platform.processor(),
                         "load_1min_before": load_before, "load_1min_after": os.getloadavg()[0],
                         "uptime_before": uptime_before,
                         "uptime_after": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
