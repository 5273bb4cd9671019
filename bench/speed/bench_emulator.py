"""Bit-exact Loihi emulation throughput vs the float32 PyTorch IR reference, in-process and as a CLI call.

Workload (the th1 workload): the paper's RSNN in the authors' layout, 48 input axons
(24 event channels = 12 taxels x 2 polarities, each fed twice) -> 450 recurrent -> 28, 270 steps,
lowered for Loihi exactly (SpyTorch order: refDelay 2, delays 1/2/1, global w_scale). Inputs:
seeded Bernoulli spikes, p = 0.02 per channel and step (SYNTHETIC) unless ``--data`` gives a .npz.
Weights: a trained snncc checkpoint or weight list if ``--model`` is given, else the authors'
initialisation N(0, 1/sqrt(fan_in)) with the feed-forward weights x ``--fwd-scale`` (2.0) and the
recurrent ones x ``--rec-scale`` (0.2; the authors' 0.01 rounds every recurrent weight to zero
under the global 8-bit scale): SYNTHETIC, untrained, chosen so that the hidden layer fires a few
% of its neurons per step and most recurrent weights are non-zero, like a trained model. The
activity measured is printed with the figures: the event-driven kernel's cost grows with it.

Figures, measured in one process, side by side (each ``--repeat`` times; best and median):
  * kernel (``PreparedNetwork.run``, network prepared once) at batch B (2,048) on 1 thread and on
    all cores: samples/s; at batch 1: ms per sample;
  * with ``--baseline-rev REV``: the kernel of that git revision (``targets/loihi/emulation/kernel.py``)
    on the same network and inputs, checked to give identical results: before vs after;
  * the float32 PyTorch IR reference (``snncc.ir.simulate``) on 1 thread and all cores, on the
    first ``--ir-samples`` (256) samples in chunks of 256 (memory): samples/s; ratio kernel / reference;
  * the kernel's CPU time per sample on 1 thread and per neuron-step (less inflated by other load);
  * the whole CLI call ``snncc emulate BUNDLE --input x.npy -o out.npz`` on the B samples, in
    fresh processes: warm (kernel caches filled) and cold (empty NUMBA_CACHE_DIR and SNNCC_CACHE_DIR: the kernel is
    compiled), beside ``python -c "import snncc.cli.main"`` (import time); with
    ``--baseline-cli-python`` also that interpreter's ``snncc`` (a venv of an earlier revision).

Also: the vector registers in the compiled kernel's machine code (``asm``: zmm = 512-bit, ymm =
256-bit; compiled afresh in a subprocess, since numba cannot show cached code), and each
performance goal beside its figure and target (``goals``, listed in bench/speed/README.md).

Other engineers share the machine: ``machine.load_1min_*`` and ``uptime`` are recorded, and the
1-minute load before each measured section (``load_1min_at``); a load above the core count
inflates every wall time (the ratios in one run drift much less).

    python bench/speed/bench_emulator.py                                 # -> bench/speed/results/emulator.json
    python bench/speed/bench_emulator.py --baseline-rev main --repeat 7
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

REPO = Path(__file__).resolve().parents[2]
IR_CHUNK = 256


def build(model: str | None, params: str | None, seed: int, fwd_scale: float, rec_scale: float):
    from snncc.frontends import LoadOptions, graph_from_object, load_model
    from snncc.models import SNNConfig, SpikingClassifier

    if model:
        return load_model(model, LoadOptions(params=params)), model
    torch.manual_seed(seed)
    module = SpikingClassifier(SNNConfig())
    module.reset_parameters(fwd_weight_scale=fwd_scale, weight_scale_factor=rec_scale)
    source = (f"authors' initialisation, feed-forward x {fwd_scale}, recurrent x {rec_scale} "
              "(SYNTHETIC, untrained; scaled for a few % hidden activity)")
    return graph_from_object(module), source


def inputs(batch: int, steps: int, base: int, copies: int, rate: float, seed: int, data: str | None):
    if data:
        with np.load(data) as z:
            x = z["inputs"][:batch]
        if x.shape[0] < batch:
            x = np.concatenate([x] * (batch // x.shape[0] + 1))[:batch]
    else:
        x = (np.random.default_rng(seed).random((batch, steps, base)) < rate).astype(np.uint8)
    return np.tile(x, (1, 1, copies)) if x.shape[2] == base else x


def timed(fn, repeat: int) -> dict:
    """Wall times of ``repeat`` runs: best (the least disturbed by other load) and median; and the
    process's CPU time of the run with the best CPU time (all its threads: less inflated by other
    load than wall time, though a busy sibling hyper-thread still slows it)."""
    times, cpu = [], []
    for _ in range(repeat):
        c0, t0 = time.process_time(), time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return {"best_s": min(times), "median_s": statistics.median(times), "cpu_best_s": min(cpu), "runs": len(times)}


def rate_of(t: dict, samples: int) -> dict:
    return {"best": samples / t["best_s"], "median": samples / t["median_s"]}


def ms_per(t: dict, samples: int) -> dict:
    return {"best": 1e3 * t["best_s"] / samples, "median": 1e3 * t["median_s"] / samples}


def _load_source(folder: Path, name: str, src: str):
    path = folder / f"{name.rsplit('_', 1)[0]}.py"
    if not path.exists() or path.read_text() != src:
        path.write_text(src)
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod          # numba's cache finds the module again by name
    spec.loader.exec_module(mod)
    return mod


def load_kernel_at(rev: str):
    """The kernel as it was at git revision ``rev``: a module with ``Flat`` and ``run_flat`` (before the program
    moved to ``emulation/flat.py``: ``kernel.py`` itself; after: that revision's ``flat.py`` over its ``kernel.py``)."""
    def show(path: str) -> str | None:
        found = subprocess.run(["git", "show", f"{rev}:{path}"], cwd=REPO, capture_output=True, text=True)
        return found.stdout if found.returncode == 0 else None

    src = show("targets/loihi/emulation/kernel.py")
    if src is None:
        raise SystemExit(f"revision {rev} has no targets/loihi/emulation/kernel.py")
    sha = subprocess.run(["git", "rev-parse", "--short", rev], cwd=REPO, capture_output=True, text=True,
                         check=True).stdout.strip()
    folder = Path(tempfile.gettempdir()) / f"snncc_bench_kernel_{sha}"   # reused: its numba cache survives
    folder.mkdir(exist_ok=True)
    kernel = _load_source(folder, f"_kernel_baseline_{sha}", src)
    flat = show("targets/loihi/emulation/flat.py")
    if flat is None:
        return kernel, sha
    flat = flat.replace("from snncc.targets.loihi.emulation.kernel import", f"from _kernel_baseline_{sha} import")
    return _load_source(folder, f"_flat_baseline_{sha}", flat), sha


def with_threads(n: int, fn):
    """Run fn under numba's and torch's thread count n (the baseline's kernel uses numba's)."""
    import numba

    before_numba, before_torch = numba.get_num_threads(), torch.get_num_threads()
    numba.set_num_threads(n)
    torch.set_num_threads(n)
    try:
        return fn()
    finally:
        numba.set_num_threads(before_numba)
        torch.set_num_threads(before_torch)


def cli_calls(net, x: np.ndarray, repeat: int, python: str | None = None) -> dict:
    """Whole ``snncc emulate`` calls in fresh processes: import, warm and cold (empty numba and C kernel caches).

    ``python``: the interpreter whose ``snncc`` to call (another venv, e.g. one installed from an
    earlier revision: the before figure); default this one."""
    from snncc.targets.loihi.bundle.write import write_bundle

    python = python or sys.executable
    snncc = Path(python).parent / "snncc"
    cmd_prefix = [str(snncc)] if snncc.exists() else [python, "-c", "from snncc.cli.main import run; run()"]
    with tempfile.TemporaryDirectory() as tmp:
        bundle, xin, out = Path(tmp) / "th1.net", Path(tmp) / "x.npy", Path(tmp) / "out.npz"
        write_bundle(net, bundle)
        np.save(xin, x)
        cmd = cmd_prefix + ["emulate", str(bundle), "--input", str(xin), "-o", str(out)]
        env = dict(os.environ)

        def run(extra_env=None):
            subprocess.run(cmd, check=True, capture_output=True, env={**env, **(extra_env or {})}, cwd=tmp)

        run()                                                   # fills the numba cache
        warm = timed(run, repeat)
        cold_dirs = [Path(tmp) / f"numba_cold_{i}" for i in range(max(1, repeat // 3))]
        cold_times = []
        for d in cold_dirs:
            t0 = time.perf_counter()
            run({"NUMBA_CACHE_DIR": str(d), "SNNCC_CACHE_DIR": str(d / "c")})   # numba's and the C kernel's
            cold_times.append(time.perf_counter() - t0)
        cold = {"best_s": min(cold_times), "median_s": statistics.median(cold_times), "runs": len(cold_times)}
        # cwd: the temporary folder, so that no checkout in the current folder shadows the install
        imp = timed(lambda: subprocess.run([python, "-c", "import snncc.cli.main"], check=True, cwd=tmp), repeat)
        bare = timed(lambda: subprocess.run([python, "-c", "pass"], check=True, cwd=tmp), repeat)
    n = x.shape[0]
    return {"command": "snncc emulate BUNDLE --input x.npy -o out.npz", "snncc": cmd_prefix[0], "samples": n,
            "warm_s": warm, "warm_samples_per_s": rate_of(warm, n),
            "cold_s": cold, "cold_samples_per_s": rate_of(cold, n),
            "import_snncc_cli_main_s": imp, "python_startup_s": bare,
            "warm_minus_import_s": {"best": warm["best_s"] - imp["best_s"],
                                    "median": warm["median_s"] - imp["median_s"]}}


ASM_PROBE = """
import json, re, sys, numpy as np, llvmlite.binding as ll
from snncc.targets.loihi.emulation import kernel as _kernel
from snncc.targets.loihi.bundle.read import read_bundle
from snncc.targets.loihi.emulation.emulator import PreparedNetwork
net = read_bundle(sys.argv[1])
PreparedNetwork(net).run(np.zeros((1, 3, net.input_width), np.uint8), threads=1)
asm = _kernel.run_chunk.inspect_asm(_kernel.run_chunk.signatures[0])
count = {r: len(re.findall("%" + r + "[0-9]", asm)) for r in ("zmm", "ymm", "xmm")}
count.update(vpmulld=asm.count("vpmulld"), vpmullq=asm.count("vpmullq"), vcvt=asm.count("vcvt"),
             host_cpu=ll.get_host_cpu_name(), avx512f="+avx512f" in ll.get_host_cpu_features().flatten())
print(json.dumps(count))
"""


def asm_vector_width(net) -> dict:
    """Vector registers named in the kernel's machine code, compiled afresh (an empty NUMBA_CACHE_DIR)."""
    from snncc.targets.loihi.bundle.write import write_bundle

    with tempfile.TemporaryDirectory() as tmp:
        bundle = Path(tmp) / "net.net"
        write_bundle(net, bundle)
        out = subprocess.run([sys.executable, "-c", ASM_PROBE, str(bundle)], capture_output=True, text=True,
                             env={**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / "cache"),
                                  "SNNCC_LOIHI_KERNEL": "numba"}, cwd=tmp, check=True)
    found = json.loads(out.stdout.strip().splitlines()[-1])
    found["note"] = ("LLVM's tuning for this CPU prefers 256-bit vectors (prefer-256-bit): numba emits ymm "
                     "(8 int32 lanes) and uses zmm only where it must")
    return found


def goal(value: float, target: float, higher: bool = True) -> dict:
    """A performance goal: the figure, the target, met?, and figure / target (> 1 is better when met)."""
    met = value >= target if higher else value <= target
    return {"value": value, "target": target, "met": met, "ratio": value / target if higher else target / value}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=2048)
    ap.add_argument("--single", type=int, default=64, help="samples timed one at a time (batch 1)")
    ap.add_argument("--rate", type=float, default=0.02, help="input spike probability per channel and step")
    ap.add_argument("--fwd-scale", type=float, default=2.0)
    ap.add_argument("--rec-scale", type=float, default=0.2)
    ap.add_argument("--model", default=None)
    ap.add_argument("--params", default=None)
    ap.add_argument("--data", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=5, help="runs of each measurement (best and median reported)")
    ap.add_argument("--ir-samples", type=int, default=256, help="samples the IR reference is timed on")
    ap.add_argument("--baseline-rev", default=None, help="git revision whose kernel to time beside this one")
    ap.add_argument("--no-cli", action="store_true", help="skip the whole-CLI-call measurement")
    ap.add_argument("--no-asm", action="store_true", help="skip the machine-code vector width probe")
    ap.add_argument("--baseline-cli-python", default=None,
                    help="also time the snncc CLI of this interpreter (e.g. a venv of an earlier revision)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "emulator.json"))
    args = ap.parse_args(argv)

    from snncc.atomic import write_text_atomic
    from snncc.ir.simulate import simulate
    from snncc.targets.loihi import target
    from snncc.targets.loihi.emulation.emulator import PreparedNetwork, program
    from snncc.targets.loihi.emulation.flat import kernel_name

    load_before = os.getloadavg()[0]
    uptime_before = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    graph, source = build(args.model, args.params, args.seed, args.fwd_scale, args.rec_scale)
    art = target.lower(graph, {"timing": "exact", "scale": "global"})
    net = art.network
    steps = net.t_sample
    k = int(graph.metadata.get("input_copies", 1))
    base = int(graph.metadata.get("base_inputs", net.input_width))
    x = inputs(args.batch, steps, base, k, args.rate, args.seed, args.data)
    single = x[: args.single]

    prepared = PreparedNetwork(net)
    prepared.run(x[:2])                                  # compile / load the kernel
    activity = prepared.run(x[: min(64, len(x))], record="all")
    rates = {f"layer{i}": float(s.mean()) for i, s in activity.spikes.items()}
    nonzero_rec = float(np.mean(net.layers[1].weight_rec != 0)) if net.layers[1].weight_rec is not None else 0.0

    load_at = {"kernel": os.getloadavg()[0]}
    kernel = {}
    for n_threads in sorted({1, cores}):
        t = timed(lambda: prepared.run(x, threads=n_threads), args.repeat)
        kernel[str(n_threads)] = {"samples_per_s": rate_of(t, len(x)), **t}
    load_at["batch1"] = os.getloadavg()[0]
    t1 = timed(lambda: [prepared.run(s, threads=1) for s in single], args.repeat)
    batch1 = ms_per(t1, len(single))
    reference = prepared.run(x)

    baseline = None
    if args.baseline_rev:
        mod, sha = load_kernel_at(args.baseline_rev)
        flat = mod.Flat(program(net))
        drive = net.drive(x)
        old = mod.run_flat(flat, drive, "outputs")                   # compile / load, and the check
        same = bool(np.array_equal(old.output_spikes, reference.output_spikes)
                    and old.overflow == reference.overflow)
        base_kernel = {}
        # a kernel whose run_flat takes ``threads`` (else it uses numba's thread count, set here)
        own_threads = "threads" in inspect.signature(mod.run_flat).parameters
        for n_threads in sorted({1, cores}):
            kw = {"threads": n_threads} if own_threads else {}
            t = with_threads(n_threads, lambda: timed(lambda: mod.run_flat(flat, drive, "outputs", **kw), args.repeat))
            base_kernel[str(n_threads)] = {"samples_per_s": rate_of(t, len(x)), **t}
        one = {"threads": 1} if own_threads else {}
        tb1 = timed(lambda: [mod.run_flat(flat, net.drive(s[None]), "outputs", **one) for s in single], args.repeat)
        baseline = {"rev": sha, "identical_results": same, "kernel_by_threads": base_kernel,
                    "batch1_ms_per_sample": ms_per(tb1, len(single))}

    x_ir = x[: args.ir_samples]

    def ir_run():
        for lo in range(0, len(x_ir), IR_CHUNK):
            simulate(graph, x_ir[lo:lo + IR_CHUNK], dtype=torch.float32)

    simulate(graph, x[:2], dtype=torch.float32)
    load_at["ir_float32"] = os.getloadavg()[0]
    ir = {}
    with torch.inference_mode():
        for n_threads in sorted({1, cores}):
            t = with_threads(n_threads, lambda: timed(ir_run, max(2, args.repeat // 2)))
            ir[str(n_threads)] = {"samples_per_s": rate_of(t, len(x_ir)), **t}
        with_threads(1, lambda: simulate(graph, single[:1], dtype=torch.float32))
        ti1 = with_threads(1, lambda: timed(lambda: [simulate(graph, s[None], dtype=torch.float32)
                                                     for s in single[:16]], max(2, args.repeat // 2)))
        pred_ir = np.asarray(simulate(graph, x[:IR_CHUNK], dtype=torch.float32).prediction)

    best_emu = max(v["samples_per_s"]["best"] for v in kernel.values())
    best_ir = max(v["samples_per_s"]["best"] for v in ir.values())
    med_emu = max(v["samples_per_s"]["median"] for v in kernel.values())
    med_ir = max(v["samples_per_s"]["median"] for v in ir.values())
    cli_repeat = max(3, args.repeat // 2 + 1)
    load_at["cli"] = os.getloadavg()[0]
    cli = None if args.no_cli else cli_calls(net, x, cli_repeat)
    asm = None if args.no_asm else asm_vector_width(net)
    cli_baseline = None
    if args.baseline_cli_python and not args.no_cli:
        cli_baseline = cli_calls(net, x, cli_repeat, python=args.baseline_cli_python)

    result = {
        "workload": {"network": " -> ".join(str(lay.n) for lay in net.layers)
                     + (" (recurrent hidden)" if net.layers[1].weight_rec is not None else ""),
                     "steps": steps, "weights": source,
                     "inputs": args.data or f"seeded Bernoulli spikes p={args.rate} per channel and step (SYNTHETIC)",
                     "spike_rates": rates, "recurrent_weights_nonzero": nonzero_rec,
                     "timing": "exact (refDelay 2, delays 1/2/1)", "w_scale": art.quantization["w_scale"],
                     "accumulator": str(np.dtype(prepared.flat.acc_dtype)),
                     "weights_stored": str(prepared.flat.wflat.dtype)},
        "kernel": kernel_name(prepared.flat),       # the C kernel where the compiler builds it (SNNCC_LOIHI_KERNEL)
        "batch": args.batch,
        "kernel_by_threads": kernel,
        "kernel_samples_per_s": {"best": best_emu, "median": med_emu},
        "batch1_ms_per_sample": batch1,
        "kernel_cpu_us_per_sample_1_thread": 1e6 * kernel["1"]["cpu_best_s"] / len(x),
        "kernel_cpu_ns_per_neuron_step_1_thread": 1e9 * kernel["1"]["cpu_best_s"] / len(x) / steps
        / sum(lay.n for lay in net.layers[1:]),
        "ir_float32_samples": len(x_ir),
        "ir_float32_by_threads": ir,
        "ir_float32_samples_per_s": {"best": best_ir, "median": med_ir},
        "ir_float32_batch1_ms_per_sample": ms_per(ti1, 16),
        "ratio_kernel_over_ir": {"best": best_emu / best_ir, "median": med_emu / med_ir},
        "baseline": baseline,
        "ratio_kernel_over_baseline": None if baseline is None else {
            "batch": best_emu / max(v["samples_per_s"]["best"] for v in baseline["kernel_by_threads"].values()),
            "batch1": baseline["batch1_ms_per_sample"]["best"] / batch1["best"]},
        "cli": cli,
        "cli_baseline": cli_baseline,
        "goals": {"kernel_batch_samples_per_s>=10000": goal(best_emu, 10_000),
                  "kernel_batch1_ms<=0.5": goal(batch1["best"], 0.5, higher=False),
                  "kernel>=10x_ir_float32": goal(best_emu / best_ir, 10),
                  "cli_samples_per_s>=1500": None if cli is None else goal(cli["warm_samples_per_s"]["best"], 1500),
                  "paper_loihi_batch1_ms<=2.3": goal(batch1["best"], 2.3, higher=False)},
        "asm": asm,
        "prediction_agreement_emulator_vs_ir_float32": float(np.mean(reference.prediction[:IR_CHUNK] == pred_ir)),
        "machine": {"cores": cores, "python": platform.python_version(), "load_1min_before": load_before,
                    "load_1min_after": os.getloadavg()[0], "load_1min_at": load_at, "uptime_before": uptime_before,
                    "uptime_after": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()},
        "note": ("wall-clock best and median of repeated runs; the machine is shared, so a load above the core "
                 "count inflates times; weights and inputs SYNTHETIC unless --model/--data"),
    }
    write_text_atomic(args.out, json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
