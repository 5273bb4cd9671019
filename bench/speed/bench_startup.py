"""Start-up time of the ``snncc`` command: ``--help``, each verb's ``--help``, and the commands that
read graphs and bundles (inspect, map, report, emulate), as whole processes.

    python bench/speed/bench_startup.py [--repeats 7] [--out bench/speed/results/startup.json]

Each figure is the median (and best) wall time of a fresh ``python -m snncc.cli.main ...`` process,
measured side by side with a bare ``python -c pass`` and ``python -c "import torch"`` in the same
run, so that the ratios hold on a loaded machine where the absolute times drift. Goal:
``snncc --help`` <= 0.5 s.

``graph_commands``: ``snncc inspect`` of the NIR paper's Braille graph and of a two-neuron graph,
and ``map`` / ``report --energy`` / ``emulate`` of that Braille graph's Loihi bundle (compiled here
first, 2 SYNTHETIC input samples). Each gives its wall time, ``import_s`` (the sum of the top-level
imports' times that ``python -X importtime`` reports, one run) and whether torch was imported.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

VERBS = ("compile", "inspect", "emulate", "check", "map", "report", "export", "run", "data", "train", "bench",
         "analyse", "hpo")
GOAL_HELP_S = 0.5
NIR = Path(__file__).resolve().parents[2] / "tests" / "data" / "nir"
BRAILLE_NIR = NIR / "braille_noDelay_noBias_subtract.nir"


def wall(argv: list[str], repeats: int) -> dict:
    """Median and best wall time of ``repeats`` fresh processes, and their median CPU time (user + system,
    less inflated than wall time when other work shares the cores)."""
    times, cpu = [], []
    for _ in range(repeats):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return {"median_s": statistics.median(times), "best_s": min(times), "cpu_median_s": statistics.median(cpu)}


def import_profile(argv: list[str]) -> dict:
    """One run under ``-X importtime``: the top-level imports' total time and whether torch was among them."""
    done = subprocess.run(argv[:1] + ["-X", "importtime"] + argv[1:], stdout=subprocess.DEVNULL,
                          stderr=subprocess.PIPE, text=True, check=False)
    total, modules = 0, set()
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cumulative, name = (part for part in line.split("|"))
        modules.add(name.strip())
        if cumulative.strip().isdigit() and not name.startswith("  "):   # a top-level import
            total += int(cumulative)
    return {"import_s": total / 1e6, "torch_imported": "torch" in modules, "exit_status": done.returncode}


def graph_commands(snncc: list[str], workdir: Path) -> dict[str, list[str]]:
    """The commands timed, on a bundle compiled here from the Braille NIR graph (and 2 input samples)."""
    import numpy as np

    bundle, x = workdir / "braille.net", workdir / "x.npy"
    subprocess.run(snncc + ["compile", str(BRAILLE_NIR), "--scale", "global", "-o", str(bundle)],
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    np.save(x, (np.random.default_rng(0).random((2, 100, 12)) < 0.1).astype(np.uint8))
    return {
        "inspect braille.nir": ["inspect", str(BRAILLE_NIR)],
        "inspect two_lif_neurons.nir --dt 1e-3": ["inspect", str(NIR / "two_lif_neurons.nir"), "--dt", "1e-3"],
        "map braille.net": ["map", str(bundle)],
        "report braille.net --energy": ["report", str(bundle), "--energy", "--samples", "2"],
        "emulate braille.net": ["emulate", str(bundle), "-i", str(x), "-o", str(workdir / "out.npz")],
    }


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
    with tempfile.TemporaryDirectory() as tmp:
        record["graph_commands"] = {name: {**wall(snncc + cmd, args.repeats), **import_profile(snncc + cmd)}
                                    for name, cmd in graph_commands(snncc, Path(tmp)).items()}
    record["machine"]["load_1min_after"] = os.getloadavg()[0]
    help_s = record["snncc_help"]["median_s"]
    record["snncc_help_over_python_bare"] = help_s / record["python_bare"]["median_s"]
    record["snncc_help_over_import_torch"] = help_s / record["python_import_torch"]["median_s"]
    record["goals"] = {"snncc_help_at_most_0.5_s": help_s <= GOAL_HELP_S,
                       "slowest_verb_help_s": max(v["median_s"] for v in record["verb_help"].values()),
                       "graph_commands_without_torch": all(not c["torch_imported"]
                                                           for c in record["graph_commands"].values())}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=2) + "\n")
    print(json.dumps(record, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
