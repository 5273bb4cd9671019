"""Xylo fine-tuning and lowering speed: the fast paths against the plain ones, side by side in one run.

Each figure is a ratio of two times taken in this run, on the same data, after checking that both paths
give the same result:

* ``training_step``: one training step (forward and backward, batch ``--batch``, 256 model steps) of the
  student that ``compile --finetune`` trains, on the Braille graph's Xylo lowering (``--replicas``,
  ``--relays``): float64 over the whole network (the path before) against float32 over the whole network
  and float32 block by block (the default on the CPU). Same output events checked.
* ``lowering``: ``lower()`` of the same graph and options with the former identification arithmetic patched
  in (kept here as the baseline: each neuron's normal equations from its weighted rows copied out of the whole
  feature matrix, built at once; rounding with error feedback updating index sets) against the current one (the
  normal equations summed over blocks of rows computed when needed and used by every neuron while they are in
  cache; rounding from one Cholesky factor). Identical specs checked. The emulator's kernels are compiled first.
* ``rounding``: rounding with error feedback alone, former against current, on seeded quadratic forms.
  Identical integers checked.

One thread for torch (as the fine-tuning engine runs); numpy's BLAS as installed. SYNTHETIC inputs.

    python bench/speed/bench_xylo_finetune.py                    # -> bench/speed/results/xylo_finetune_speed.json
    python bench/speed/bench_xylo_finetune.py --relays both      # the Xylo goal's lowering (minutes per lowering)
    python bench/speed/bench_xylo_finetune.py --quick            # one copy (one block), fewer forms, one repeat
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

BRAILLE_NIR = REPO / "tests" / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def training_step(args, low) -> dict:
    import torch

    from snncc.targets.xylo.finetune.arithmetic import DifferentiableXylo
    from snncc.targets.xylo.finetune.tuning import lowered_student, surrogate_units

    student = lowered_student(low, 256)
    core = student.core
    out = next(r for r in low.populations if r.role == "output")
    x = (np.random.default_rng(0).random((args.batch, 256, 12)) < 0.08).astype(np.float64)
    chip_x = student.chip_input(torch.as_tensor(x))
    variants = {"float64, whole network": (torch.float64, False), "float32, whole network": (torch.float32, False),
                "float32, block by block": (torch.float32, True)}
    times, counts = {}, {}
    for name, (dtype, by_blocks) in variants.items():
        model = DifferentiableXylo(low.xylo_spec, core.steps, core.hidden, out.name, unit=surrogate_units(low),
                                   unit_out=np.asarray(out.units, np.float64), dtype=dtype, by_blocks=by_blocks)

        def step(model=model, name=name):
            model.zero_grad()
            run = model(chip_x)
            (run.counts.sum() + sum(v.sum() for v in run.voltage.values())).backward()
            counts[name] = run.counts.detach().double().numpy()

        step()
        times[name] = best_of(step, args.repeat)
    same = all(np.array_equal(c, counts["float64, whole network"]) for c in counts.values())
    base = times["float64, whole network"]
    return {"network": f"{BRAILLE_NIR.name} lowered with --replicas {args.replicas} --relays {args.relays}: "
                       f"{low.xylo_spec.n_hidden} hidden neurons, {len(core.hidden)} populations",
            "batch": args.batch, "model_steps": 256, "chip_steps": core.steps,
            "seconds": times, "same_output_events": same,
            "speedup_vs_float64_whole": {k: base / v for k, v in times.items()}}


def per_neuron_normal_equations(d, neurons):
    """The former normal equations (baseline): each neuron's weighted rows copied out of the whole feature matrix."""
    from snncc.targets.xylo.lowering.regression import ROW_FLOOR

    out = []
    for j in neurons:
        w = d.weight[:, j]
        keep = w >= ROW_FLOOR
        a = d.features[keep] * w[keep, None]
        out.append((a.T @ a, a.T @ (d.target[keep, j] * w[keep])))
    return out


def former_rounding(h, c, step, low=-128, high=127, last=None):
    """The former ``round_with_feedback`` (baseline): the free coefficients as an index set, updated by fancy
    indexing after each rounding."""
    one = np.ndim(c) == 1
    c = np.array(np.asarray(c, np.float64), ndmin=2)
    n = c.shape[1]
    step = np.broadcast_to(np.asarray(step, np.float64), (n,))
    low, high = np.broadcast_to(low, (n,)), np.broadcast_to(high, (n,))
    hinv = np.linalg.inv(np.asarray(h, np.float64))
    free = np.ones(n, bool)
    out = np.zeros(c.shape, np.int64)
    order = [i for i in np.argsort(-np.diag(h), kind="stable") if i != last] + ([last] if last is not None else [])
    for i in order:
        k = np.clip(np.round(c[:, i] / step[i]), low[i], high[i]).astype(np.int64)
        out[:, i] = k
        err = c[:, i] - k * step[i]
        free[i] = False
        idx = np.flatnonzero(free)
        if idx.size:
            c[:, idx] -= np.outer(err, hinv[idx, i] / hinv[i, i])
            hinv[np.ix_(idx, idx)] -= np.outer(hinv[idx, i], hinv[i, idx]) / hinv[i, i]
    return out[0] if one else out


def former_hidden_normal_equations(sources, decays, v_pre, theta, scale, constant, neurons=None):
    """The former hidden populations' normal equations (baseline): the whole feature matrix built at once, each
    neuron's weighted rows copied out of it."""
    from snncc.targets.xylo.lowering.regression import design

    d = design(sources, decays, v_pre, theta, scale, constant)
    return per_neuron_normal_equations(d, range(v_pre.shape[2]) if neurons is None else neurons)


@contextmanager
def former_arithmetic():
    """The Xylo lowering with the former normal equations and rounding patched in."""
    from snncc.targets.xylo.lowering import integers, regression

    saved = regression.hidden_normal_equations, integers.round_with_feedback
    regression.hidden_normal_equations = former_hidden_normal_equations
    integers.round_with_feedback = former_rounding
    try:
        yield
    finally:
        regression.hidden_normal_equations, integers.round_with_feedback = saved


def lowering(args, graph) -> tuple[dict, object]:
    from snncc.targets.xylo.lowering.lower import lower
    from snncc.targets.xylo.options import XyloOptions

    options = XyloOptions(replicas=args.replicas, relays=args.relays, time_steps=256)
    lower(graph, XyloOptions(replicas=args.replicas, relays=args.relays, calibration_samples=8, time_steps=16))
    t0 = time.perf_counter()
    with former_arithmetic():
        before = lower(graph, options)
    t1 = time.perf_counter()
    now = lower(graph, options)
    t2 = time.perf_counter()
    same = before.spec.keys() == now.spec.keys() and all(np.array_equal(np.asarray(before.spec[k]),
                                                                         np.asarray(now.spec[k])) for k in now.spec)
    return ({"options": {k: v for k, v in options.as_dict().items() if v is not None}, "rule": now.rule, "seconds": {"former arithmetic": t1 - t0, "current": t2 - t1},
             "identical_spec": same, "speedup": (t1 - t0) / (t2 - t1)}, now)


def rounding(args) -> dict:
    from snncc.targets.kit.compute import round_with_feedback

    rng = np.random.default_rng(2)
    cases = []
    for _ in range(args.forms):
        a = rng.normal(size=(4 * args.coefficients, args.coefficients))
        cases.append((a.T @ a, rng.normal(scale=20, size=args.coefficients)))
    same = all(np.array_equal(round_with_feedback(h, c, 0.5), former_rounding(h, c, 0.5)) for h, c in cases)
    t_old = best_of(lambda: [former_rounding(h, c, 0.5) for h, c in cases], args.repeat)
    t_new = best_of(lambda: [round_with_feedback(h, c, 0.5) for h, c in cases], args.repeat)
    return {"forms": args.forms, "coefficients": args.coefficients, "identical_integers": same,
            "seconds": {"index sets (before)": t_old, "Cholesky factor": t_new}, "speedup": t_old / t_new}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(REPO / "bench" / "speed" / "results" / "xylo_finetune_speed.json"))
    ap.add_argument("--replicas", type=int, default=4)
    ap.add_argument("--relays", default="fast", choices=("fast", "both"))
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--forms", type=int, default=40)
    ap.add_argument("--coefficients", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="one replica, fewer forms, one repeat")
    args = ap.parse_args(argv)
    if args.quick:
        args.replicas, args.forms, args.repeat = 1, 10, 1
    import torch

    from snncc.frontends import LoadOptions, load_model

    torch.set_num_threads(1)
    load = os.getloadavg()
    graph = load_model(BRAILLE_NIR, LoadOptions(dt=1e-4, reset="subtract"))
    low_figures, low = lowering(args, graph)
    result = {"machine": {"platform": platform.platform(), "python": platform.python_version(),
                          "torch": torch.__version__, "cores": os.cpu_count(), "load_before": load},
              "inputs": "SYNTHETIC (seeded random spikes and quadratic forms)",
              "lowering": low_figures, "training_step": training_step(args, low), "rounding": rounding(args)}
    result["machine"]["load_after"] = os.getloadavg()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    lo = result["lowering"]
    print(f"lowering ({BRAILLE_NIR.name}, --replicas {args.replicas} --relays {args.relays}): "
          f"{lo['seconds']['former arithmetic']:.1f} s -> {lo['seconds']['current']:.1f} s ({lo['speedup']:.2f}x), "
          f"identical spec: {lo['identical_spec']}")
    ts = result["training_step"]
    print(f"training step ({ts['network']}, batch {ts['batch']}):")
    for name, sec in ts["seconds"].items():
        print(f"  {name}: {sec:.2f} s  ({ts['speedup_vs_float64_whole'][name]:.2f}x)")
    print(f"  same output events: {ts['same_output_events']}")
    ro = result["rounding"]
    print(f"rounding with error feedback ({ro['forms']} forms of {ro['coefficients']}): "
          f"{ro['seconds']['index sets (before)']:.2f} s -> {ro['seconds']['Cholesky factor']:.2f} s "
          f"({ro['speedup']:.2f}x), identical integers: {ro['identical_integers']}")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
