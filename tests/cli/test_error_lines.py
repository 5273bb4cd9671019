"""Usage errors, operating-system refusals, Ctrl-C and hostile pickles: one line, the right status."""

from __future__ import annotations

import errno
import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from snncc_test_helpers import run_cli, without_progress


def one_error_line(code: int, err: str, status: int = 2) -> str:
    """The one line a failure ends with (progress lines before it, printed outside a terminal, set aside)."""
    lines = [line for line in without_progress(err).splitlines() if line.strip()]
    assert code == status, err
    assert len(lines) == 1 and lines[0].startswith("snncc: "), err
    assert "Traceback" not in err and "internal error" not in err
    return lines[0]


@pytest.mark.parametrize("args, says", [
    (["compile"], "Missing argument"),
    (["compile", "m.pt"], "Missing option"),
    (["compile", "m.pt", "-o", "x", "--no-such-option"], "No such option"),
    (["frobnicate"], "no such command"),
    (["train", "rsnn", "--data", "d", "-o", "x.pt", "--epochs", "many"], "--epochs"),
    (["emulate", "b.net", "-i", "x.npy", "-o", "o.npz", "--gap", "1.5"], "--gap"),
])
def test_usage_errors_are_one_line_with_status_2(tmp_path, monkeypatch, capsys, args, says):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args, capsys)
    assert says in one_error_line(code, err)
    assert list(tmp_path.iterdir()) == []


def test_bare_snncc_shows_the_verbs_and_exits_2(capsys):
    code, out, err = run_cli([], capsys)
    assert code == 2 and "compile" in out + err and "Traceback" not in err


def test_os_refusals_are_one_line(tmp_path, small_rsnn_checkpoint, capsys, monkeypatch):
    import tempfile as tempfile_module

    def refused(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied", str(tmp_path / "out"))

    monkeypatch.setattr(tempfile_module, "mkstemp", refused)
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "ir", "-o", tmp_path / "out" / "m.snnir"], capsys)
    assert "EACCES" in one_error_line(code, err)


def test_a_full_disk_during_writing_leaves_nothing(tmp_path, small_rsnn_checkpoint, capsys, monkeypatch):
    def disk_full(self, data):
        raise OSError(errno.ENOSPC, "No space left on device", str(self))

    monkeypatch.setattr(Path, "write_bytes", disk_full)
    for args in (["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", tmp_path / "b.net"],
                 ["export", small_rsnn_checkpoint, "--to", "nir", "-o", tmp_path / "m.nir"]):
        code, _, err = run_cli(args, capsys)
        assert "ENOSPC" in one_error_line(code, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rsnn.pt"]


def mount_tmpfs(path: Path, options: str) -> bool:
    path.mkdir(parents=True, exist_ok=True)
    out = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)], capture_output=True)
    return out.returncode == 0


@pytest.fixture
def small_mounts(tmp_path):
    """A 64 KiB tmpfs (fills up) and a read-only one, where this machine lets the tests mount."""
    full, ro = tmp_path / "full", tmp_path / "ro"
    if os.geteuid() != 0 or not mount_tmpfs(full, "size=64k"):
        pytest.skip("mounting a small tmpfs needs root (the in-process ENOSPC test covers the logic)")
    mount_tmpfs(ro, "ro,size=16k")
    yield full, ro
    for mount in (full, ro):
        subprocess.run(["umount", str(mount)], capture_output=True)


def test_real_full_and_read_only_disks_give_one_line_and_no_crash(small_mounts, tmp_path):
    full, ro = small_mounts
    import numpy as np
    import torch

    from snncc.frontends.checkpoint import save_checkpoint
    from snncc.models import SNNConfig, SpikingClassifier

    model = tmp_path / "big.pt"   # its NIR export (~150 KB) cannot fit in 64 KiB
    save_checkpoint(SpikingClassifier(SNNConfig(n_hidden=180, n_outputs=28)), model, {"dt": 0.005})
    (full / "filler").write_bytes(np.zeros(8 * 1024, np.uint8).tobytes())
    for out, code_name in ((full / "m.nir", "ENOSPC"), (ro / "m.nir", "EROFS")):
        proc = subprocess.run([sys.executable, "-m", "snncc.cli.main", "export", str(model), "--to", "nir", "-o",
                               str(out)], capture_output=True, text=True, timeout=300)
        assert code_name in one_error_line(proc.returncode, proc.stderr)
    assert sorted(p.name for p in full.iterdir()) == ["filler"]
    assert list(ro.iterdir()) == []
    del torch


def default_sigint() -> None:
    """In the child: Ctrl-C's default action, even where the test runner was started with SIGINT
    ignored (a background job of a non-interactive shell), so Python installs its handler."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


READY_THEN_RUN = (   # the console script's own call, run() reading sys.argv; 'ready' once inside it
    "from snncc.cli import main\n"
    "dispatch = main._dispatch\n"
    "def announced(*args):\n"
    "    print('ready', flush=True)\n"
    "    return dispatch(*args)\n"
    "main._dispatch = announced\n"
    "main.run()\n"
)


def test_ctrl_c_at_any_moment_prints_one_line_and_exits_130(small_rsnn_checkpoint, tmp_path):
    """SIGINT while snncc imports torch, lowers, validates or writes: one line, status 130, no output.

    The signal is sent a measured time after snncc's own code has started (the interpreter's own
    start-up, before any snncc code runs, is Python's to handle)."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    interrupted = 0
    for delay in (0.0, 0.5, 1.5, 3.0):
        out = tmp_path / f"b{delay}.net"
        proc = subprocess.Popen([sys.executable, "-c", READY_THEN_RUN, "compile", str(small_rsnn_checkpoint),
                                 "-t", "loihi", "-o", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, env=env, preexec_fn=default_sigint)
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(delay)
        if proc.poll() is not None:   # finished before the signal: nothing to interrupt
            proc.communicate()
            continue
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        if proc.returncode == 0:       # the signal came as it was exiting
            continue
        assert "interrupted" in one_error_line(proc.returncode, err, status=130)
        assert not out.exists()
        interrupted += 1
    assert interrupted >= 1
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".part")] == []


class Payload:
    """A pickle that runs a command when loaded by a plain unpickler."""

    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


@pytest.mark.parametrize("verb", ["encode", "train", "analyse"])
def test_braille_pickle_with_a_payload_is_refused_without_running_it(tmp_path, capsys, verb):
    marker = tmp_path / "payload_ran"
    data_dir = tmp_path / "data"
    data_dir.mkdir()
    evil = data_dir / "data_braille_letters_raw.pkl"
    evil.write_bytes(pickle.dumps([{"letter": "A", "taxel_data": Payload(marker)}]))
    args = {"encode": ["data", "encode", evil, "--threshold", "1", "-o", tmp_path / "e.npz"],
            "train": ["train", "lstm", "--data", data_dir, "-o", tmp_path / "m.pt", "--epochs", "1"],
            "analyse": ["data", "analyse", data_dir]}[verb]
    code, _, err = run_cli(args, capsys)
    assert "refused without running it" in one_error_line(code, err)
    assert not marker.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["data"]


def test_published_layouts_still_load_through_the_restricted_unpickler(tmp_path):
    import numpy as np

    from snncc.data import formats

    raw = np.random.default_rng(0).integers(0, 256, (3, 10, 12))
    for release in (1, 2):
        path = tmp_path / f"r{release}" / formats.RAW_NAME
        path.parent.mkdir()
        formats.write_raw(path, raw, np.array([0, 1, 2]), release=release)
        loaded = formats.load_raw(path)
        assert loaded.release == release and np.array_equal(loaded.raw, raw)


def test_ctrl_c_turned_into_another_error_by_a_library_still_reads_as_interrupted(tmp_path, capsys, monkeypatch):
    import snncc.frontends

    def interrupted_import(*args, **kwargs):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as ex:
            raise ImportError("partially initialised module") from ex

    monkeypatch.setattr(snncc.frontends, "load_model", interrupted_import)
    model = tmp_path / "m.pt"
    model.write_bytes(b"x")
    code, _, err = run_cli(["compile", model, "-t", "ir", "-o", tmp_path / "o.snnir"], capsys)
    assert "interrupted" in one_error_line(code, err, status=130)
