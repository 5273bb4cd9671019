"""Fixtures of the HPO tests: a small synthetic Braille directory, the CLI in a subprocess, storage reads."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

SNNCC = [sys.executable, "-m", "snncc.cli.main"]


@pytest.fixture(scope="session")
def braille_dir(tmp_path_factory):
    """27 letters x 7 repetitions (SYNTHETIC, seed 5), threshold-1 events and raw frames, with the marker."""
    from snncc.data import formats
    from snncc.data.sigma_delta import encode
    from snncc.data.sources import MARKER
    from snncc.data.synth import generate

    d = tmp_path_factory.mktemp("hpo_braille")
    raw, labels = generate(7, seed=5)
    formats.write_raw(d / formats.RAW_NAME, raw, labels, release=1)
    formats.write_events(d / formats.events_name(1), encode(255 - raw.astype("int64"), 1), labels, release=1)
    (d / MARKER).write_text(json.dumps({"synthetic": True, "seed": 5, "repetitions": 7}))
    return d


def tiny_args(data, workdir) -> list[str]:
    """A tiny, fast search: 8 hidden neurons, 10 ms bins (135 steps), 1-2 input copies, 2 samples for energy."""
    return ["--data", str(data), "--threshold", "1", "--hidden", "8", "--range", "time_bin_size=10",
            "--range", "nb_input_copies=1:2", "--energy-samples", "2", "--batch-size", "64", "--startup", "1",
            "--heartbeat", "1", "--dir", str(workdir), "--quiet", "--device", "cpu"]


def env() -> dict:
    e = dict(os.environ)
    e.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1", COLUMNS="200")
    return e


def start(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen(SNNCC + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env())


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


def wait_until(condition, proc: subprocess.Popen, timeout: float = 180) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return
        if proc.poll() is not None:
            out, err = proc.communicate()
            raise AssertionError(f"the worker ended early ({proc.returncode}): {err[-2000:]}")
        time.sleep(0.2)
    proc.kill()
    raise AssertionError("timed out")
