"""No command destroys a user's file: outputs over inputs, foreign directories, kills, leftovers."""

from __future__ import annotations

import os
import shutil

import numpy as np
import pytest

from snncc_test_helpers import run_cli
from snncc.atomic import atomic_dir, clean_leftovers, exchange
from snncc.errors import SnnccError


def one_error_line(code: int, err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("snncc: error: "), err
    assert "Traceback" not in err
    return lines[0]


def snapshot(directory) -> dict:
    return {p.relative_to(directory).as_posix(): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


@pytest.fixture
def bundle(tmp_path, small_rsnn_checkpoint, capsys):
    path = tmp_path / "b.net"
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", path], capsys)
    assert code == 0, err
    return path


@pytest.mark.parametrize("target", ["loihi", "ir"])
def test_compile_output_onto_its_input_is_refused(tmp_path, small_rsnn_checkpoint, capsys, target):
    before = snapshot(tmp_path)
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", target, "-o", small_rsnn_checkpoint], capsys)
    assert "input of this command" in one_error_line(code, err)
    assert snapshot(tmp_path) == before


def test_output_through_a_symlink_to_the_input_is_refused(tmp_path, small_rsnn_checkpoint, capsys):
    link = tmp_path / "link.net"
    link.symlink_to(small_rsnn_checkpoint)
    before = snapshot(tmp_path)
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "--output=" + str(link)], capsys)
    one_error_line(code, err)
    assert snapshot(tmp_path) == before and link.is_symlink()


def test_export_onto_its_input_is_refused(tmp_path, small_rsnn_checkpoint, capsys):
    before = snapshot(tmp_path)
    code, _, err = run_cli(["export", small_rsnn_checkpoint, "--to", "nir", "-o", small_rsnn_checkpoint], capsys)
    one_error_line(code, err)
    assert snapshot(tmp_path) == before


def test_emulate_onto_its_inputs_is_refused(tmp_path, bundle, capsys):
    x = tmp_path / "x.npy"
    np.save(x, (np.random.default_rng(0).random((2, 20, 24)) < 0.1).astype(np.uint8))
    before = snapshot(tmp_path)
    for out in (x, bundle):
        code, _, err = run_cli(["emulate", bundle, "-i", x, "-o", out], capsys)
        one_error_line(code, err)
        assert snapshot(tmp_path) == before


def test_jetson_output_into_a_user_directory_deletes_nothing(tmp_path, small_rsnn_checkpoint, capsys, monkeypatch):
    user_dir = tmp_path / "mine"
    user_dir.mkdir()
    (user_dir / "thesis.tex").write_text("years of work")
    before = snapshot(tmp_path)
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "jetson", "-o", user_dir, "--time-steps", "20"],
                           capsys)
    assert "not replaceable" in one_error_line(code, err)
    assert snapshot(tmp_path) == before
    monkeypatch.chdir(user_dir)
    for name in (".", ".."):
        code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "jetson", "-o", name, "--time-steps", "20"],
                               capsys)
        one_error_line(code, err)
    assert snapshot(tmp_path) == before


def test_jetson_directory_holding_the_input_is_refused(tmp_path, small_rsnn_checkpoint, capsys):
    art = tmp_path / "art"
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "jetson", "-o", art, "--time-steps", "20"], capsys)
    assert code == 0, err
    model = art / "model.pt"
    shutil.copy(small_rsnn_checkpoint, model)
    before = snapshot(tmp_path)
    code, _, err = run_cli(["compile", model, "-t", "jetson", "-o", art, "--time-steps", "20"], capsys)
    line = one_error_line(code, err)
    assert "contains an input" in line or "not replaceable" in line
    assert snapshot(tmp_path) == before


def test_previous_jetson_artefact_is_replaced_but_not_with_a_user_file_inside(tmp_path, small_rsnn_checkpoint, capsys):
    art = tmp_path / "art"
    args = ["compile", small_rsnn_checkpoint, "-t", "jetson", "-o", art, "--time-steps", "20"]
    code, _, err = run_cli(args, capsys)
    assert code == 0, err
    (art / "model.plan").write_bytes(b"engine built on the board")   # build_engine.sh's output is ours
    code, _, err = run_cli(args, capsys)
    assert code == 0, err
    assert not (art / "model.plan").exists() and (art / "manifest.json").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    (art / "notes.txt").write_text("mine")
    code, _, err = run_cli(args, capsys)
    assert "notes.txt" in one_error_line(code, err)
    assert (art / "notes.txt").read_text() == "mine"


def test_file_output_naming_an_existing_directory_is_refused(tmp_path, small_rsnn_checkpoint, capsys):
    target_dir = tmp_path / "d"
    target_dir.mkdir()
    (target_dir / "keep").write_text("x")
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", target_dir], capsys)
    assert "is a directory" in one_error_line(code, err)
    assert (target_dir / "keep").read_text() == "x"


def test_leftovers_of_killed_runs_are_cleaned_and_live_ones_kept(tmp_path, small_rsnn_checkpoint, capsys):
    dead_pid = 2 ** 22 + 12345   # above the default pid_max: no such process
    dead = tmp_path / f".out.net.{dead_pid}.abcd.part"
    dead.write_bytes(b"half")
    dead_dir = tmp_path / f".out.net.{dead_pid}.efgh.part"
    dead_dir.mkdir()
    live = tmp_path / f".out.net.{os.getppid()}.ijkl.part"   # the parent of this process runs
    live.write_bytes(b"someone else's write in progress")
    other = tmp_path / ".unrelated.part"
    other.write_bytes(b"not ours")
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", tmp_path / "out.net"], capsys)
    assert code == 0, err
    assert not dead.exists() and not dead_dir.exists()
    assert live.exists() and other.exists()


def make_artefact(path, text):
    path.mkdir()
    (path / "manifest.json").write_text(text)


def test_directory_swap_is_atomic_or_recoverable(tmp_path, monkeypatch):
    dest = tmp_path / "art"
    make_artefact(dest, "old")
    ours = lambda d: None  # noqa: E731  (every directory counts as ours here)
    with atomic_dir(dest, replaceable=ours) as tmp:
        (tmp / "manifest.json").write_text("new")
    assert (dest / "manifest.json").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["art"]

    # Without the kernel's exchange, the fallback is two renames; a kill between them leaves the
    # old directory as .art.PID.x.old, which the next write puts back before anything else.
    real_rename = os.rename
    calls = []

    def killed_after_first_rename(a, b):
        calls.append((a, b))
        real_rename(a, b)
        if len(calls) == 1:
            raise KeyboardInterrupt

    monkeypatch.setattr(os, "rename", killed_after_first_rename)
    with pytest.raises(KeyboardInterrupt):
        with atomic_dir(dest, replaceable=ours, swap=lambda a, b: False) as tmp:
            (tmp / "manifest.json").write_text("newer")
    monkeypatch.setattr(os, "rename", real_rename)
    assert not dest.exists()
    (old,) = [p for p in tmp_path.iterdir() if p.name.endswith(".old")]
    # Pretend the killed process is gone: rename its .old to a dead pid's name.
    old = old.rename(tmp_path / ".art.4206969.x.old")
    clean_leftovers(dest)
    assert (dest / "manifest.json").read_text() == "new" and not old.exists()


def test_kernel_exchange_swaps_two_directories(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    make_artefact(a, "A")
    make_artefact(b, "B")
    if exchange(a, b):
        assert (a / "manifest.json").read_text() == "B" and (b / "manifest.json").read_text() == "A"
    else:  # a kernel or file system without RENAME_EXCHANGE: nothing was touched
        assert (a / "manifest.json").read_text() == "A"


def test_existing_directory_without_replaceable_rule_is_refused(tmp_path):
    dest = tmp_path / "d"
    dest.mkdir()
    with pytest.raises(SnnccError, match="not replaceable"):
        with atomic_dir(dest):
            pass


def test_devices_as_inputs_are_refused_and_as_outputs_written_through(tmp_path, small_rsnn_checkpoint, capsys):
    """/dev/zero as an input never hangs or fills memory; -o /dev/null never replaces the device node."""
    for args in (["compile", "/dev/zero", "-t", "ir", "-o", tmp_path / "x.snnir"],
                 ["data", "encode", "/dev/zero", "-t", "1", "-o", tmp_path / "e.npz"]):
        code, _, err = run_cli(args, capsys)
        assert "not a regular file" in one_error_line(code, err)
    before = os.stat("/dev/null")
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "ir", "-o", "/dev/null"], capsys)
    assert code == 0, err
    after = os.stat("/dev/null")
    assert (after.st_mode, after.st_rdev, after.st_ino) == (before.st_mode, before.st_rdev, before.st_ino)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rsnn.pt"]


@pytest.mark.parametrize("kind", ["directory", "symlink"])
def test_jetson_replacement_checks_kinds_not_only_names(tmp_path, small_rsnn_checkpoint, capsys, kind):
    """A directory (or symlink) named like a file the manifest lists is a user's, not snncc's: refused."""
    art = tmp_path / "art"
    args = ["compile", small_rsnn_checkpoint, "-t", "jetson", "-o", art, "--time-steps", "20"]
    code, _, err = run_cli(args, capsys)
    assert code == 0, err
    (art / "step.onnx").unlink()
    if kind == "directory":
        (art / "step.onnx").mkdir()
        (art / "step.onnx" / "notes.txt").write_text("mine")
    else:
        (tmp_path / "elsewhere.onnx").write_text("mine")
        (art / "step.onnx").symlink_to(tmp_path / "elsewhere.onnx")
    before = snapshot(tmp_path)
    code, _, err = run_cli(args, capsys)
    assert "step.onnx is not a regular file" in one_error_line(code, err)
    assert snapshot(tmp_path) == before
    assert (art / "step.onnx").is_symlink() == (kind == "symlink")


def test_hpo_report_never_writes_its_figure_over_the_study_storage(tmp_path, capsys):
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    work = tmp_path / "D"
    work.mkdir()
    optuna.create_study(study_name="s", storage=f"sqlite:///{work / 'hpo.sqlite3'}")
    optuna.create_study(study_name="s", storage=f"sqlite:///{work / 'other.db'}")
    before = snapshot(tmp_path)
    for args in (["--dir", work, "-o", work / "hpo.sqlite3"],
                 ["--storage", f"sqlite:///{work / 'other.db'}", "-o", work / "other.db"]):
        code, _, err = run_cli(["hpo", "report", "s", *args], capsys)
        assert "is an input of this command" in one_error_line(code, err)
        assert snapshot(tmp_path) == before


def test_compile_checks_its_output_before_compiling(tmp_path, small_rsnn_checkpoint, capsys, monkeypatch):
    """-o onto the input, '.', a directory for a file, a file for a directory: refused before the model is read."""
    import snncc.frontends.buffered

    def no_loading(*args, **kwargs):
        raise AssertionError("the model was loaded before the output was checked")

    monkeypatch.setattr(snncc.frontends.buffered, "load_compilable", no_loading)
    (tmp_path / "d").mkdir()
    (tmp_path / "f.txt").write_text("mine")
    monkeypatch.chdir(tmp_path)
    before = snapshot(tmp_path)
    for target, out, says in (("loihi", small_rsnn_checkpoint, "is an input of this command"),
                              ("jetson", ".", "names a directory"), ("loihi", tmp_path / "d", "is a directory"),
                              ("jetson", tmp_path / "f.txt", "a file of that name exists")):
        code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", target, "-o", out], capsys)
        assert says in one_error_line(code, err)
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("target", ["jetson", "xylo", "c"])
def test_a_user_directory_is_refused_before_anything_is_lowered(target, tmp_path, shared_nir, capsys, monkeypatch):
    """A directory target refuses an existing directory it did not write at once (the writer's own rule, asked
    before the compilation and its checks), not after minutes of lowering: the lowering is never reached."""
    def lowering(*args, **kwargs):
        raise AssertionError("the model was lowered before the output was refused")

    monkeypatch.setattr("snncc.targets.capability", lowering)
    user_dir = tmp_path / "mine"
    user_dir.mkdir()
    (user_dir / "notes.txt").write_text("mine")
    before = snapshot(tmp_path)
    code, _, err = run_cli(["compile", shared_nir / "braille_noDelay_noBias_subtract.nir", "--dt", "1e-4", "--reset",
                            "subtract", "-t", target, "-o", user_dir], capsys)
    assert "not replaceable" in one_error_line(code, err)
    assert snapshot(tmp_path) == before
