"""Run every benchmark, one after another, and gather their JSON into bench/speed/results/all.json.

    python bench/speed/run_all.py [--quick]

Runs the speed and cost benchmarks of bench/speed/ listed in ``benches`` (the longer ones, such as
bench_loihi_scale.py, bench_xylo_costs.py and c_target.py, run on their own: bench/speed/README.md)
and, after them, two agreement studies from bench/studies/ (nir_loihi_agreement.py and
cnn_sinabs_agreement.py), as it did before bench/ was split; the other studies run on their own
(bench/studies/README.md). Each benchmark measures its ratios side by side within its own run
(absolute times drift on shared machines); every record carries the machine's load. --quick shrinks
the workloads.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCH = HERE.parent                     # the scripts below are named relative to bench/
RESULTS = HERE / "results"


def benches(quick: bool) -> list[tuple[str, list[str], Path | None]]:
    """(name, argv (the script relative to bench/), JSON file it writes or None when it prints JSON on stdout)."""
    return [
        ("startup", ["speed/bench_startup.py", "--out", str(RESULTS / "startup.json")]
         + (["--repeats", "3"] if quick else []), RESULTS / "startup.json"),
        ("compile", ["speed/bench_compile.py", "--out", str(RESULTS / "compile.json")], RESULTS / "compile.json"),
        ("emulator", ["speed/bench_emulator.py", "--out", str(RESULTS / "emulator.json")]
         + (["--batch", "256", "--single", "16"] if quick else []), RESULTS / "emulator.json"),
        ("xylo_emulator", ["speed/bench_xylo_emulator.py", "--out", str(RESULTS / "xylo_emulator.json")]
         + (["--quick"] if quick else []), RESULTS / "xylo_emulator.json"),
        ("xylo_finetune_speed", ["speed/bench_xylo_finetune.py", "--out", str(RESULTS / "xylo_finetune_speed.json")]
         + (["--quick"] if quick else []), RESULTS / "xylo_finetune_speed.json"),
        ("emulator_cnn", ["speed/bench_emulator_cnn.py", "--out", str(RESULTS / "emulator_cnn.json")]
         + (["--samples", "4", "--repeat", "3"] if quick else []), RESULTS / "emulator_cnn.json"),
        ("jetson", ["speed/bench_jetson.py", "--json-out", str(RESULTS / "jetson.json")]
         + (["--samples", "5", "--repeats", "1"] if quick else []), RESULTS / "jetson.json"),
        ("mapping", ["speed/bench_mapping.py", "--out", str(RESULTS / "mapping.json")]
         + (["--neurons", "100000"] if quick else []), RESULTS / "mapping.json"),
        ("energy", ["speed/bench_energy.py", "--json"] + (["--samples", "8"] if quick else []), None),
        ("nir_loihi_agreement", ["studies/nir_loihi_agreement.py", "--json"]
         + (["--samples", "50", "--seeds", "0", "--no-trained"] if quick else []), None),
        ("cnn_sinabs_agreement", ["studies/cnn_sinabs_agreement.py", "--json"]
         + (["--samples", "8", "--steps", "40", "--density", "0.05"] if quick else []), None),
    ]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller workloads (minutes instead of tens of minutes)")
    args = ap.parse_args(argv)
    RESULTS.mkdir(exist_ok=True)
    gathered: dict[str, object] = {"started": time.strftime("%Y-%m-%dT%H:%M:%S"), "quick": args.quick,
                                   "cores": os.cpu_count()}
    failed = []
    for name, cmd, json_file in benches(args.quick):
        print(f"== {name}: python bench/{' '.join(cmd)}", flush=True)
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, str(BENCH / cmd[0]), *cmd[1:]], capture_output=True, text=True)
        if proc.returncode != 0:
            failed.append(name)
            gathered[name] = {"error": (proc.stderr.strip().splitlines() or ["failed"])[-1]}
            print(f"   failed: {gathered[name]['error']}")
            continue
        try:
            record = json.loads(json_file.read_text()) if json_file else json.loads(proc.stdout[proc.stdout.index("{"):])
        except (ValueError, OSError) as ex:
            record = {"error": f"no JSON result ({ex})"}
            failed.append(name)
        gathered[name] = record
        print(f"   done in {time.perf_counter() - t0:.0f} s")
    (RESULTS / "all.json").write_text(json.dumps(gathered, indent=2))
    print(f"wrote {RESULTS / 'all.json'}" + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
