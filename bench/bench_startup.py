"""Start-up time of the ``snncc`` command: ``--help`` and each verb's ``--help``, as whole processes.

    python bench/bench_startup.py [--repeats 7] [--out bench/results/startup.json]

Each figure is the median (and best) wall time of a fresh ``python -m snncc.cli.main ...`` process,
measured side by side with a bare ``python -c pass`` and ``python -c "import torch"`` in the same
run, so that the ratios hold on a loaded machine where the absolute times drift. Goal (issue 13):
``snncc --help`` <= 0.5 s.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

VERBS = ("compile", "inspect", "emulate", "check", "map", "report", "export", "run", "data", "train", "bench",
         "analyse", "hpo")
GOAL_HELP_S = 0.5


def wall(argv: list[str], repeats: int) -> dict:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times.append(time.perf_counter() - t0)
    return {"median_s": statistics.median(times), "best_s": min(times)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results" / "startup.json")
    args = ap.parse_args(argv)
    py = [sys.executable]
    snncc = py + ["-m", "snncc.cli.main"]
    record = {
        "machine": {"cores": os.cpu_count(), "load_1min_before": os.getloadavg()[0]},
        "python_bare": wall(py + ["-c", "pass"], args.repeats),
        "python_import_torch": wall(py + ["-c", "import torch"], args.repeats),
        "snncc_help": wall(snncc + ["--help"], args.repeats),
        "verb_help": {verb: wall(snncc + [verb, "--help"], args.repeats) for verb in VERBS},
    }
    record["machine"]["load_1min_after"] = os.getloadavg()[0]
    help_s = record["snncc_help"]["median_s"]
    record["snncc_help_over_python_bare"] = help_s / record["python_bare"]["median_s"]
    record["snncc_help_over_import_torch"] = help_s / record["python_import_torch"]["median_s"]
    record["goals"] = {"snncc_help_at_most_0.5_s": help_s <= GOAL_HELP_S,
                       "slowest_verb_help_s": max(v["median_s"] for v in record["verb_help"].values())}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(json.dumps(record, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
