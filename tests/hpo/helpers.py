"""Helpers of the HPO tests: the CLI in a subprocess, cheap reads of a study's storage."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

SNNCC = [sys.executable, "-m", "snncc.cli.main"]


def tiny_args(data, workdir) -> list[str]:
    """A tiny, fast search: 8 hidden neurons, 10 ms bins (135 steps), 1-2 input copies, 2 samples for energy."""
    return ["--data", str(data), "--threshold", "1", "--hidden", "8", "--range", "time_bin_size=10",
            "--range", "nb_input_copies=1:2", "--energy-samples", "2", "--batch-size", "64", "--startup", "1",
            "--heartbeat", "1", "--dir", str(workdir), "--quiet", "--device", "cpu"]


def env() -> dict:
    e = dict(os.environ)
    e.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1", COLUMNS="200")
    return e


def default_sigint() -> None:
    """In the child: Ctrl-C's default action, even where the test runner was started with SIGINT
    ignored (a background job of a non-interactive shell), so Python installs its handler."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen(SNNCC + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env(),
                            preexec_fn=default_sigint)


def run(args: list[str], timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run(SNNCC + args, capture_output=True, text=True, env=env(), timeout=timeout)


def trials(workdir, name: str) -> list:
    """The study's trials as stored (empty while it does not exist yet)."""
    import optuna

    db = workdir / "hpo.sqlite3"
    if not db.is_file():
        return []
    try:
        return optuna.load_study(study_name=name, storage=f"sqlite:///{db}").get_trials(deepcopy=False)
    except KeyError:
        return []
    except Exception:   # the database is being created this instant
        return []


def states(workdir) -> list[tuple[int, str, int | None]]:
    """A cheap poll of the SQLite file: (trial number, state, last reported epoch) of every trial."""
    import sqlite3

    db = workdir / "hpo.sqlite3"
    if not db.is_file():
        return []
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=5) as con:
            return con.execute("SELECT t.number, t.state, MAX(v.step) FROM trials t LEFT JOIN "
                               "trial_intermediate_values v ON v.trial_id = t.trial_id GROUP BY t.trial_id").fetchall()
    except sqlite3.Error:   # the tables are being created this instant
        return []


def wait_until(condition, proc: subprocess.Popen, timeout: float = 180) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return
        if proc.poll() is not None:
            out, err = proc.communicate()
            raise AssertionError(f"the worker ended early ({proc.returncode}): {err[-2000:]}")
        time.sleep(0.05)
    proc.kill()
    raise AssertionError("timed out")
