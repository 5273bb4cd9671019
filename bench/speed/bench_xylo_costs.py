"""What Xylo costs a user, this tree against an earlier commit, side by side in one run.

Every figure is a separate ``snncc`` process, as a user runs it: CPU seconds (user + system of the process and
its threads, ``os.wait4``'s rusage, what ``/usr/bin/time -v`` reports) and peak resident memory (its
``ru_maxrss``). The earlier commit runs from a copy of its ``snncc/`` and ``targets/`` (``git archive``) on the
same interpreter and packages (``PYTHONPATH``); both trees' numba kernels are compiled once before timing (their
caches warm, as on an installed machine). Runs alternate before / after.

    compile            snncc compile braille_noDelay_noBias_subtract.nir --dt 1e-4 --reset subtract --target xylo
                       (``--replicas 4 --relays both`` too), as a user runs it (thread pools as installed) and with
                       every pool pinned to one thread (OMP / OPENBLAS / MKL / NUMBA_NUM_THREADS=1); spec.npz of
                       both trees compared byte for byte
    emulate            snncc emulate of one 256-step sample of the default artefact
    check              snncc check --artefact of the default artefact without data: 1,000 seeded random samples
                       (and 10,000 for this tree: the earlier one needs about 45 GB there)

    python bench/speed/bench_xylo_costs.py --before 663c876                  # -> bench/speed/results/xylo_costs.json
    python bench/speed/bench_xylo_costs.py --before 663c876 --after HEAD      # both from git (edits meanwhile harmless)
    python bench/speed/bench_xylo_costs.py --before 663c876 --quick          # the default compile and emulate only

Every compile gives ``--time-steps 256`` (the calibration's length before this round, and snncc's default time
base once it is 256), so both trees do the same work and write the same spec.npz.

Other work may share the machine: ``machine`` records the load; CPU seconds drift less than wall time, and the
ratios are of runs made minutes apart.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
NIR = REPO / "tests" / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
MODEL = ["--dt", "1e-4", "--reset", "subtract"]
STEPS = ["--time-steps", "256"]
PINNED = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}


def earlier_tree(commit: str, where: Path) -> Path:
    """``snncc/`` of ``commit`` with its ``targets/`` as ``snncc/targets``: importable from ``where`` on PYTHONPATH."""
    archive = subprocess.run(["git", "-C", str(REPO), "archive", commit, "snncc", "targets"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive, check=True)
    shutil.move(str(where / "targets"), str(where / "snncc" / "targets"))
    return where


def run(args: list[str], tree: Path | None, pinned: bool, cwd: Path) -> dict:
    """One ``snncc`` process: CPU seconds (user + system), peak RSS, wall seconds, exit status."""
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    if pinned:
        env.update(PINNED)
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "snncc.cli.main", *args], env=env, cwd=cwd,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    return {"cpu_s": usage.ru_utime + usage.ru_stime, "user_s": usage.ru_utime, "sys_s": usage.ru_stime,
            "peak_rss_mb": usage.ru_maxrss / 1024, "wall_s": time.perf_counter() - t0,
            "exit": os.waitstatus_to_exitcode(status), "stderr_tail": err.strip().splitlines()[-1:] if err else []}


def pair(name: str, args_of, trees: dict[str, Path | None], pinned: bool, cwd: Path, out: dict) -> None:
    row = {}
    for label, tree in trees.items():
        row[label] = run(args_of(label), tree, pinned, cwd)
        print(f"{name} [{label}{', pinned' if pinned else ''}]: {row[label]['cpu_s']:.1f} s CPU, "
              f"{row[label]['peak_rss_mb']:.0f} MB, exit {row[label]['exit']}", flush=True)
    if "before" in row and "after" in row:
        row["cpu_ratio_before_over_after"] = row["before"]["cpu_s"] / row["after"]["cpu_s"]
        row["rss_ratio_before_over_after"] = row["before"]["peak_rss_mb"] / row["after"]["peak_rss_mb"]
    out[name + (" (pinned to one thread)" if pinned else "")] = row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default=None, help="the earlier commit to compare with (default: none, this tree only)")
    ap.add_argument("--after", default=None, help="the later commit (default: this working tree)")
    ap.add_argument("--quick", action="store_true", help="the default compile and emulate only")
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "speed" / "results" / "xylo_costs.json")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="snncc-xylo-costs-") as tmp:
        tmp = Path(tmp)
        after: Path | None = None
        if args.after:
            (tmp / "after").mkdir()
            after = earlier_tree(args.after, tmp / "after")
        trees: dict[str, Path | None] = {"after": after}
        if args.before:
            (tmp / "before").mkdir()
            trees = {"before": earlier_tree(args.before, tmp / "before"), "after": after}
        work = tmp / "work"
        work.mkdir()
        x = (np.random.default_rng(0).random((1, 256, 12)) < 0.08).astype(np.uint8)
        np.save(work / "one.npy", x)
        for label, tree in trees.items():          # every kernel compiled (or loaded from its cache) once
            warm = run(["compile", str(NIR), *MODEL, "--target", "xylo", "--rule", "relayed", "--calibration-samples",
                        "4", "--time-steps", "16", "-o", f"warm_{label}.xylo"], tree, False, work)
            assert warm["exit"] == 0, warm
            run(["emulate", f"warm_{label}.xylo", "--input", "one.npy", "-o", f"warm_{label}.npz"], tree, False, work)
        figures: dict = {}
        compile_default = lambda label: ["compile", str(NIR), *MODEL, *STEPS, "--target", "xylo", "-o",   # noqa: E731
                                         f"default_{label}.xylo"]
        pair("compile (default rule)", compile_default, trees, False, work, figures)
        pair("compile (default rule)", compile_default, trees, True, work, figures)
        same = {}
        if args.before:
            same["compile (default rule)"] = (work / "default_before.xylo" / "spec.npz").read_bytes() == \
                (work / "default_after.xylo" / "spec.npz").read_bytes()
        pair("emulate one sample", lambda label: ["emulate", f"default_{label}.xylo", "--input", "one.npy", "-o",
                                                  f"one_{label}.npz"], trees, False, work, figures)
        if not args.quick:
            both = lambda label: ["compile", str(NIR), *MODEL, *STEPS, "--target", "xylo", "--replicas", "4",   # noqa: E731
                                  "--relays", "both", "-o", f"both_{label}.xylo"]
            pair("compile --replicas 4 --relays both", both, trees, False, work, figures)
            pair("compile --replicas 4 --relays both", both, trees, True, work, figures)
            if args.before:
                same["compile --replicas 4 --relays both"] = (work / "both_before.xylo" / "spec.npz").read_bytes() == \
                    (work / "both_after.xylo" / "spec.npz").read_bytes()
            check = lambda label: ["check", str(NIR), *MODEL, "--artefact", f"default_{label}.xylo"]   # noqa: E731
            pair("check --artefact, 1,000 samples", check, trees, False, work, figures)
            pair("check --artefact, 10,000 samples",
                 lambda label: [*check(label), "--samples", "10000"], {"after": after}, False, work, figures)
    result = {"what": "Xylo's costs as a user runs snncc: CPU seconds (user + system) and peak RSS per process",
              "before": args.before, "after": args.after or "the working tree at " + subprocess.run(
                  ["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip(),
              "commands": {"compile": "snncc compile braille_noDelay_noBias_subtract.nir --dt 1e-4 --reset subtract "
                                      "--time-steps 256 --target xylo [--replicas 4 --relays both] -o X.xylo",
                           "emulate": "snncc emulate X.xylo --input one.npy -o out.npz   (one.npy: (1, 256, 12) spikes)",
                           "check": "snncc check braille_noDelay_noBias_subtract.nir --dt 1e-4 --reset subtract "
                                    "--artefact X.xylo [--samples 10000]",
                           "pinned": " ".join(f"{k}=1" for k in PINNED)},
              "identical_spec_npz": same, "figures": figures,
              "machine": {"cores": os.cpu_count(), "platform": platform.platform(), "load": os.getloadavg()}}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
