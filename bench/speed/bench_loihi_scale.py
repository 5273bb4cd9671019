"""Loihi compile, emulate and start-up at scale: every goal beside its figure, measured in one run, CPU seconds.

Figures (each a fresh ``snncc`` process unless said; CPU = user + system seconds of that process and its threads,
from ``resource.getrusage(RUSAGE_CHILDREN)``, less inflated than wall time on a shared machine):

  * compile of the NIR RSNN 48 -> N dense-recurrent -> 28 (``loihi_rsnn_graphs.py``: CubaLIF tau_syn 5 ms, tau_mem
    20 ms, weights ~ N(0, 1/fan-in), biases, dt 1 ms) for N in ``--hidden``, default options: CPU, synapses,
    CPU per synapse, and the scale rule auto chose (the goal: N = 3,600 at most 15 s; per synapse within 1.5x
    from the smallest to the largest N: the largest over the smallest)
  * ``snncc emulate`` of one sample of a th1-sized bundle (48 -> 450 recurrent -> 28, 270 steps), warm (at most
    0.8 s CPU), and of 2,048 samples, beside a one-thread batched float32 torch loop of the same network (its
    float weights, decays, delays and refractory period) timed in the same run (the goal: at least 5x, wall)
  * compile of a 1-neuron NIR graph, warm, and whether numba compiled anything (``NUMBA_DEBUG_CACHE``) (at most
    2 s CPU, no numba compile)
  * ``snncc emulate --help`` wall (at most 0.5 s; the CLI's start-up is the core's) and what importing the Loihi
    target's modules costs (fresh interpreters)
  * the part of each compile spent in the float IR reference (``snncc.ir.simulate``, torch today) and in
    ``import torch``: in-process, the same compile profiled

    python bench/speed/bench_loihi_scale.py                         # -> bench/speed/results/loihi_scale.json
    python bench/speed/bench_loihi_scale.py --hidden 450 900 --repeat 1
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

HERE = Path(__file__).resolve().parent


def snncc_cmd() -> list[str]:
    exe = Path(sys.executable).parent / "snncc"
    return [str(exe)] if exe.exists() else [sys.executable, "-c", "from snncc.cli.main import run; run()"]


def child_run(cmd: list[str], env: dict | None = None, cwd: str | None = None) -> dict:
    """One process: its CPU (user + sys, with its threads), wall, exit status and output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, **(env or {})}, cwd=cwd)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"cpu_s": cpu, "wall_s": wall, "code": proc.returncode, "stdout": proc.stdout, "stderr": proc.stderr}


def best_of(cmd: list[str], repeat: int, **kw) -> dict:
    runs = [child_run(cmd, **kw) for _ in range(repeat)]
    bad = [r for r in runs if r["code"] != 0]
    if bad:
        raise SystemExit(f"{' '.join(cmd)} failed: {bad[0]['stderr'][-2000:]}")
    return {"cpu_best_s": min(r["cpu_s"] for r in runs), "wall_best_s": min(r["wall_s"] for r in runs),
            "runs": len(runs), "last": runs[-1]}


def synapses_of(bundle: Path) -> int:
    from snncc.targets.loihi.bundle.read import read_bundle

    net = read_bundle(bundle)
    return int(sum(np.count_nonzero(lay.weight) + (0 if lay.weight_rec is None else np.count_nonzero(lay.weight_rec))
                   for lay in net.layers[1:]))


def scale_rule_of(stdout: str) -> str:
    line = next((ln for ln in stdout.splitlines() if ln.startswith("Loihi bundle")), "")
    return line.split("scale rule ")[-1].split(",")[0].strip("'") if "scale rule" in line else ""


def in_process_split(graph_path: Path, dt: float) -> dict:
    """The same compile in this process, profiled: CPU in the float IR reference (snncc.ir.simulate) and in
    importing torch (measured in a fresh interpreter)."""
    import cProfile
    import pstats

    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.loihi import target

    graph = load_model(graph_path, LoadOptions(dt=dt))
    # a full lowering: this process lowers nothing before it (every other compile here is a child process), so
    # lower_model's in-process cache of recent lowerings holds nothing it could return
    pr = cProfile.Profile()
    c0 = time.process_time()
    pr.enable()
    target.lower(graph, {})
    pr.disable()
    total = time.process_time() - c0
    stats = pstats.Stats(pr).stats
    simulate = sum(v[3] for k, v in stats.items() if k[0].endswith("snncc/ir/simulate.py") and k[2] == "simulate")
    torch_import = child_run([sys.executable, "-c", "import torch"])["cpu_s"]
    return {"lower_cpu_s_profiled": total, "in_ir_simulate_s_profiled": simulate, "import_torch_cpu_s": torch_import,
            "note": "profiled times run slower than unprofiled ones; the split, not the total, is the figure"}


def torch_loop(bundle: Path, x: np.ndarray) -> dict:
    """One-thread batched float32 torch loop of the bundle's network: float weights w_chip / threshold, the decays,
    every synaptic delay (one-step delivery + extra) and the refractory period, reset to zero."""
    import torch

    from snncc.targets.loihi.bundle.read import read_bundle

    net = read_bundle(bundle)
    torch.set_num_threads(1)
    xin = torch.as_tensor(net.drive(x), dtype=torch.float32)
    batch, steps, _ = xin.shape
    layers = []
    for lay in net.layers[1:]:
        th = float(np.max(lay.v_th_mant)) * 64.0
        w = torch.as_tensor(np.asarray(lay.weight, np.float64) * 2.0 ** (6 + np.asarray(lay.wgt_exp)) / th,
                            dtype=torch.float32).T.contiguous()
        rec = None if lay.weight_rec is None else torch.as_tensor(
            np.asarray(lay.weight_rec, np.float64) * 2.0 ** (6 + np.asarray(lay.wgt_exp_rec)) / th,
            dtype=torch.float32).T.contiguous()
        layers.append({"w": w, "rec": rec, "d": int(np.max(lay.delay)), "dr": int(np.max(lay.delay_rec)),
                       "a": 1.0 - float(np.max(lay.i_decay)) / 4096, "b": 1.0 - float(np.max(lay.v_decay)) / 4096,
                       "ref": int(lay.ref_delay), "n": lay.n})
    c0, t0 = time.process_time(), time.perf_counter()
    with torch.no_grad():
        prev = [xin[:, t] for t in range(steps)]
        for L in layers:
            u = torch.zeros(batch, L["n"])
            v = torch.zeros(batch, L["n"])
            r = torch.zeros(batch, L["n"])
            out = []
            for t in range(steps):
                q = prev[t - 1 - L["d"]] @ L["w"] if t - 1 - L["d"] >= 0 else 0.0
                if L["rec"] is not None and t - 1 - L["dr"] >= 0:
                    q = q + out[t - 1 - L["dr"]] @ L["rec"]
                u = L["a"] * u + q
                v = L["b"] * v + u
                hold = r > 0
                v = torch.where(hold, torch.zeros_like(v), v)
                r = torch.where(hold, r - 1, r)
                s = (v > 1.0).float()
                v = v * (1 - s)
                r = torch.where(s > 0, torch.full_like(r, L["ref"] - 1), r)
                out.append(s)
            prev = out
    return {"cpu_s": time.process_time() - c0, "wall_s": time.perf_counter() - t0, "samples": batch, "steps": steps}


def th1_bundle(work: Path) -> tuple[Path, np.ndarray]:
    """A th1-sized bundle (48 -> 450 recurrent -> 28, 270 steps: bench_emulator's workload) and 2,048 inputs."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_emulator", HERE / "bench_emulator.py")
    be = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(be)
    from snncc.targets.loihi import target

    graph, _ = be.build(None, None, 0, 2.0, 0.2)
    art = target.lower(graph, {"timing": "exact", "scale": "global"})
    path = work / "th1.net"
    art.write(path)
    x = be.inputs(2048, art.network.t_sample, 24, 2, 0.02, 0, None)
    return path, x


def goal(value: float, target: float, at_most: bool = True) -> dict:
    return {"value": value, "target": target, "met": (value <= target) if at_most else (value >= target)}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hidden", type=int, nargs="+", default=[450, 900, 1800, 3600])
    ap.add_argument("--repeat", type=int, default=2, help="runs of each short measurement (the best is reported)")
    ap.add_argument("--no-split", action="store_true", help="skip the in-process profile of the largest compile")
    ap.add_argument("--out", default=str(HERE / "results" / "loihi_scale.json"))
    args = ap.parse_args(argv)
    import importlib.util

    spec = importlib.util.spec_from_file_location("loihi_rsnn_graphs", HERE / "loihi_rsnn_graphs.py")
    graphs = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(graphs)

    snncc = snncc_cmd()
    out: dict = {"machine": {"cores": os.cpu_count(), "load_1min_before": os.getloadavg()[0],
                             "python": sys.version.split()[0]}}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        paths = {n: graphs.write(graphs.rsnn(n), work / f"rsnn_{n}.nir") for n in args.hidden}
        one = graphs.write(graphs.one_neuron(), work / "one_neuron.nir")
        # warm: the numba cache holds the kernels (a warm install), the kernels' signatures included
        child_run(snncc + ["compile", str(paths[args.hidden[0]]), "--dt", "1e-3", "--target", "loihi",
                           "-o", str(work / "warm.net")])
        compiles = {}
        for n, path in paths.items():
            run = best_of(snncc + ["compile", str(path), "--dt", "1e-3", "--target", "loihi",
                                   "-o", str(work / f"r{n}.net")], 1 if n >= 1800 else args.repeat)
            syn = synapses_of(work / f"r{n}.net")
            compiles[str(n)] = {"cpu_s": run["cpu_best_s"], "wall_s": run["wall_best_s"], "synapses": syn,
                                "cpu_us_per_synapse": 1e6 * run["cpu_best_s"] / syn,
                                "scale_rule": scale_rule_of(run["last"]["stdout"])}
            print(n, json.dumps(compiles[str(n)]), flush=True)
        per = [c["cpu_us_per_synapse"] for c in compiles.values()]
        out["compile_nir_rsnn"] = compiles
        largest = str(max(args.hidden))
        out["goals"] = {
            f"compile_{largest}_cpu_s<=15": goal(compiles[largest]["cpu_s"], 15.0),
            "compile_cpu_per_synapse_largest_over_smallest<=1.5": goal(per[-1] / per[0], 1.5),
        }
        out["compile_cpu_per_synapse_max_over_min"] = max(per) / min(per)
        if not args.no_split:
            out["compile_split_largest"] = in_process_split(paths[max(args.hidden)], 1e-3)
        numba_env = {"NUMBA_DEBUG_CACHE": "1"}
        one_run = best_of(snncc + ["compile", str(one), "--dt", "1e-3", "--target", "loihi", "-o",
                                   str(work / "one.net")], args.repeat + 1, env=numba_env)
        compiled = "data saved" in one_run["last"]["stdout"] + one_run["last"]["stderr"]
        out["compile_one_neuron"] = {"cpu_s": one_run["cpu_best_s"], "wall_s": one_run["wall_best_s"],
                                     "numba_compiled": compiled}
        out["goals"]["compile_one_neuron_cpu_s<=2"] = goal(one_run["cpu_best_s"], 2.0)
        out["goals"]["compile_one_neuron_numba_compiles==0"] = goal(int(compiled), 0)
        bundle, x = th1_bundle(work)
        np.save(work / "x1.npy", x[:1])
        np.save(work / "x2048.npy", x)
        # the default kernel (C, where the compiler builds it) and the numba kernel side by side, each warm
        runs = {}
        for kernel in ("auto", "numba"):
            env = {"SNNCC_LOIHI_KERNEL": kernel}
            warm = child_run(snncc + ["emulate", str(bundle), "--input", str(work / "x2048.npy"), "-o",
                                      str(work / "w.npz"), "--json"], env=env)
            one_emu = best_of(snncc + ["emulate", str(bundle), "--input", str(work / "x1.npy"), "-o",
                                       str(work / "o1.npz")], args.repeat + 1, env=env)
            many = best_of(snncc + ["emulate", str(bundle), "--input", str(work / "x2048.npy"), "-o",
                                    str(work / "o.npz")], args.repeat, env=env)
            ran = json.loads(warm["stdout"]).get("implementation")
            runs[kernel] = {"kernel": ran,
                            "one_sample": {"cpu_s": one_emu["cpu_best_s"], "wall_s": one_emu["wall_best_s"]},
                            "samples_2048": {"cpu_s": many["cpu_best_s"], "wall_s": many["wall_best_s"]}}
        loop = torch_loop(bundle, x)
        one_emu, many = runs["auto"]["one_sample"], runs["auto"]["samples_2048"]
        out["emulate_th1"] = {**runs["auto"], "numba_kernel": runs["numba"],
                              "torch_float32_loop_one_thread": loop,
                              "ratio_torch_over_emulate_wall": loop["wall_s"] / many["wall_s"],
                              "ratio_torch_over_emulate_cpu": loop["cpu_s"] / many["cpu_s"],
                              "ratio_torch_over_emulate_numba_kernel_wall":
                                  loop["wall_s"] / runs["numba"]["samples_2048"]["wall_s"]}
        one_emu = {"cpu_best_s": one_emu["cpu_s"]}
        many = {"wall_best_s": many["wall_s"]}
        out["goals"]["emulate_one_sample_cpu_s<=0.8"] = goal(one_emu["cpu_best_s"], 0.8)
        out["goals"]["emulate_2048_vs_torch_loop>=5x"] = goal(loop["wall_s"] / many["wall_best_s"], 5.0, at_most=False)
        helped = best_of(snncc + ["emulate", "--help"], args.repeat + 1)
        out["emulate_help"] = {"wall_s": helped["wall_best_s"], "cpu_s": helped["cpu_best_s"]}
        out["goals"]["emulate_help_wall_s<=0.5"] = goal(helped["wall_best_s"], 0.5)
        imports = {}
        for module in ("snncc.targets.loihi.capabilities", "snncc.targets.loihi.bundle.read",
                       "snncc.targets.loihi.emulation.emulator", "snncc.targets.loihi.emulation.kernel",
                       "snncc.targets.loihi.emulation.ckernel",
                       "snncc.targets.loihi.lowering.lower"):
            base = child_run([sys.executable, "-c", "import numpy"])["cpu_s"]
            imports[module] = child_run([sys.executable, "-c", f"import numpy, {module}"])["cpu_s"] - base
        out["import_cpu_s_beyond_numpy"] = imports
    out["machine"]["load_1min_after"] = os.getloadavg()[0]
    out["note"] = ("CPU seconds of fresh processes (best of --repeat); the machine is shared, so wall times are "
                   "inflated by other load; SYNTHETIC weights and inputs")
    text = json.dumps(out, indent=2)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text + "\n")
    print(json.dumps(out["goals"], indent=2))


if __name__ == "__main__":
    main()
