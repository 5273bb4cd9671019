"""The C target's goals, measured: agreement, bit-exactness, instructions per step, flash and RAM.

    python bench/speed/c_target.py [--samples 1000] [--density 0.08] [--th1 DIR] [--out bench/speed/results/c_target.json]

For each NIR Braille graph (``braille_noDelay_noBias_subtract.nir`` with ``--dt 1e-4 --reset subtract``, the reset
kept; ``braille_zero_2023.nir`` with ``--dt 1e-4``), compiled as ``snncc compile MODEL --target c`` does (rule
``auto``, no fine-tuning):

* agreement with the float graph on ``--samples`` seeded random spike trains (``snncc check``'s own inputs:
  density 0.08, seed 0, the artefact's 100 steps; SYNTHETIC) beside the float graph's own 1 % weight-noise ceiling;
* the same inputs through the emulator, the host C (gcc -O2) and the Cortex-M4 build in QEMU: output spikes equal
  or not, and the instructions per step QEMU counted (SysTick under -icount shift=0), at those inputs' measured
  event rates and at densities 0.02 and 0.2 beside them;
* flash (snn.o text for a Cortex-M4 at -Os, measured) and RAM (sizeof(snn_state_t)) against the STM32L431RC
  (256 kB / 64 kB, 80 MHz), and the real-time verdict at dt = 1e-4 s (8,000 cycles) under the CPI assumption.

With ``--th1 DIR`` (the output directory of ``python examples/braille/run_pipeline.py --out DIR``: its
``rsnn_th1.pt`` and the test split ``rsnn_test.npz``): the RSNN compiled by ``auto`` for the STM32L431RC (which
keeps int8 there: the int16 rules do not fit its flash) and by ``--rule per-neuron-16`` (the best agreement, twice
the flash), each run in QEMU on the whole test split, accuracy beside the float graph's; flash and RAM on the part.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
NIR = ROOT / "tests" / "data" / "nir"
GRAPHS = (("braille_noDelay_noBias_subtract.nir", "subtract"), ("braille_zero_2023.nir", None))
PART = "stm32l431rc"


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def _since(start: tuple[float, float]) -> dict[str, float]:
    return {"wall_s": round(time.perf_counter() - start[0], 2), "cpu_s": round(time.process_time() - start[1], 2)}


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(a.shape == b.shape and np.array_equal(a, b))


def braille_goal(name: str, reset: str | None, samples: int, density: float, work: Path) -> dict:
    from snncc import api
    from snncc.targets import get_target
    from snncc.targets.kit.agreement import random_inputs

    target = get_target("c")
    model = NIR / name
    out = work / name.replace(".nir", "_c")
    started = _clock()
    compiled = api.compile(model, output=out, target="c", dt=1e-4, reset=reset).as_dict()
    compile_time = _since(started)
    started = _clock()
    check = api.check(model, artefact=out, dt=1e-4, reset=reset, samples=samples, density=density).as_dict()
    check_time = _since(started)
    manifest = json.loads((out / "manifest.json").read_text())
    steps = manifest["time_base"]["steps"]
    x = random_inputs(samples, steps, manifest["network"]["inputs"], density, 0)     # check's own inputs
    emulated = target.emulate(out, x).arrays()["output_spikes"]
    started = _clock()
    host = target.run(out, x, backend="host").arrays()["output_spikes"]
    host_time = _since(started)
    started = _clock()
    qemu_run = target.run(out, x, backend="qemu")
    qemu_time = _since(started)
    timing = {f"{density:g}": qemu_run.as_dict()["timing"]}
    for other in (0.02, 0.2):
        timing[f"{other:g}"] = target.run(out, random_inputs(64, steps, manifest["network"]["inputs"], other, 1),
                                          backend="qemu").as_dict()["timing"]
    report = api.report(out, energy=True, input=None, samples=samples, rate=density, seed=0).as_dict()
    usage = api.map(out).as_dict()
    return {
        "model": name, "reset": reset or "zero (NIR's v_reset)", "compile": {**compile_time, "sha256":
                                                                            compiled.get("sha256")},
        "rule": manifest["arithmetic"]["rule"], "selection": manifest["selection"],
        "agreement": {"share": check["argmax_agreement"], "low": check["argmax"]["low"],
                      "high": check["argmax"]["high"], "decided": check["argmax"]["decided"],
                      "agreeing": check["argmax"]["agreeing"], "samples": check["samples"], "steps": check["steps"],
                      "inputs": check["inputs"], **check_time},
        "ceiling": {"noise": check["ceiling"]["noise"], "share": check["ceiling"]["argmax_agreement"],
                    "low": check["ceiling"]["argmax"]["low"], "high": check["ceiling"]["argmax"]["high"]},
        "goal_agreement_at_least_ceiling": bool(check["argmax_agreement"] >= check["ceiling"]["argmax_agreement"]),
        "stages": {s["key"]: s["agreement"]["share"] for s in check["stages"]}, "causes": check["causes"],
        "bit_exact": {"emulator_equals_host_c": _same(emulated, host),
                      "emulator_equals_qemu_cortex_m4": _same(emulated, qemu_run.arrays()["output_spikes"]),
                      "samples": samples, "steps": steps, "host": host_time, "qemu": qemu_time},
        "instructions_per_step": timing,
        "event_rates": report["event_rates"],
        "realtime": report["timing"],
        "memory": {"flash_bytes": usage["fit"]["flash_bytes"], "flash_counted": usage["fit"]["flash_counted"],
                   "ram_bytes": usage["fit"]["ram_bytes"], "part": usage["fit"]["part"],
                   "flash_limit": usage["fit"]["flash_limit"], "ram_limit": usage["fit"]["ram_limit"],
                   "fits": usage["fit"]["fits"]},
    }


def th1_goal(directory: Path, work: Path) -> dict:
    from snncc import api
    from snncc.targets import get_target
    from snncc.targets.kit.inputs import load_dataset

    target = get_target("c")
    model, data = directory / "rsnn_th1.pt", directory / "rsnn_test.npz"
    x, labels, _ = load_dataset(data)
    result: dict = {"model": str(model), "data": str(data), "samples": int(len(labels))}
    for label, rule in (("auto", None), ("per-neuron-16", "per-neuron-16")):
        out = work / f"th1_{label}"
        started = _clock()
        api.compile(model, output=out, target="c", **({"rule": rule} if rule else {}))
        compile_time = _since(started)
        check = api.check(model, artefact=out, data=data).as_dict()
        started = _clock()
        ran = target.run(out, x, backend="qemu")
        qemu_time = _since(started)
        predicted = ran.arrays()["prediction"]
        emulated = target.emulate(out, x).arrays()
        usage = api.map(out).as_dict()
        manifest = json.loads((out / "manifest.json").read_text())
        result[label] = {
            "rule": manifest["arithmetic"]["rule"], "compile": compile_time,
            "float_accuracy": check["accuracy"]["float"], "emulator_accuracy": check["accuracy"]["artefact"],
            "qemu_accuracy": float(np.mean(predicted == labels)),
            "qemu_minus_float_points": 100 * (float(np.mean(predicted == labels)) - check["accuracy"]["float"]),
            "agreement": check["argmax_agreement"], "decided": check["argmax"]["decided"],
            "qemu_equals_emulator": _same(ran.arrays()["output_spikes"], emulated["output_spikes"]),
            "qemu": qemu_time, "timing": ran.as_dict()["timing"],
            "memory": {"flash_bytes": usage["fit"]["flash_bytes"], "ram_bytes": usage["fit"]["ram_bytes"],
                       "part": usage["fit"]["part"], "fits": usage["fit"]["fits"],
                       "flash_counted": usage["fit"]["flash_counted"]},
        }
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--density", type=float, default=0.08)
    ap.add_argument("--th1", default=None, help="run_pipeline.py's output directory (rsnn_th1.pt, rsnn_test.npz)")
    ap.add_argument("--out", default=str(ROOT / "bench" / "speed" / "results" / "c_target.json"))
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    results: dict = {"bench": "bench/speed/c_target.py", "part": PART, "samples": args.samples, "density": args.density}
    with tempfile.TemporaryDirectory(prefix="snncc-c-bench-") as tmp:
        for name, reset in GRAPHS:
            results[name] = braille_goal(name, reset, args.samples, args.density, Path(tmp))
            print(json.dumps({k: results[name][k] for k in ("model", "rule", "agreement", "ceiling", "bit_exact")}))
        if args.th1:
            results["th1_rsnn"] = th1_goal(Path(args.th1), Path(tmp))
            print(json.dumps(results["th1_rsnn"]))
    Path(args.out).write_text(json.dumps(results, indent=2, default=float) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
