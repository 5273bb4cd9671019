"""A third-party target plugs in through the ``snncc.targets`` entry point, with only the capabilities
it has and an option of its own (``--toy-precision``), offered by the CLI, validated by the target
and read by its ``lower`` and ``check``, from the command line and from ``snncc.api``, with no edit in
snncc; the option records refuse what a target does not take, in today's words."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import snncc.api as api
from snncc.errors import SnnccError
from snncc.targets import available_targets, capability, get_target, offered_options, target_options
from snncc.targets.ir import IROptions
from snncc.targets.jetson.capabilities import JetsonOptions
from snncc.targets.loihi.capabilities import LoihiOptions

from snncc_test_helpers import run_cli

HERE = Path(__file__).resolve().parent


def install_toy(root: Path) -> Path:
    """A package ``snncc_toy`` and its ``*.dist-info`` (METADATA, entry_points.txt) under ``root``."""
    shutil.copy(HERE / "toy_target_source.py", root / "snncc_toy.py")
    info = root / "snncc_toy-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: snncc-toy\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[snncc.targets]\ntoy = snncc_toy:target\n")
    return root


@pytest.fixture
def toy(tmp_path, monkeypatch):
    root = tmp_path / "site"
    root.mkdir()
    monkeypatch.syspath_prepend(str(install_toy(root)))
    yield root
    sys.modules.pop("snncc_toy", None)


@pytest.fixture
def toy_data(tmp_path):
    rng = np.random.default_rng(0)
    path = tmp_path / "d.npz"
    np.savez(path, inputs=(rng.random((6, 30, 48)) < 0.2).astype(np.uint8), labels=rng.integers(0, 28, 6))
    return path


def test_the_toy_target_is_found_through_its_entry_point(toy):
    assert "toy" in available_targets()
    assert type(get_target("toy")).__name__ == "ToyTarget"


def test_compile_and_check_with_a_third_party_target(toy, toy_data, small_rsnn_checkpoint, tmp_path, capsys):
    out = tmp_path / "m.toy"
    code, stdout, err = run_cli(["compile", small_rsnn_checkpoint, "--target", "toy", "-o", out,
                                 "--time-steps", "30", "--json"], capsys)
    assert code == 0, err
    written = json.loads(out.read_text())
    assert written["time_steps"] == 30 and written["nodes"] >= 3
    sha = hashlib.sha256(out.read_bytes()).hexdigest()
    assert json.loads(stdout) == {"target": "toy", "target_rule": "--target", "output": str(out), "warnings": [],
                                  "sha256": sha, "sha256_rule": "SHA-256 of the file's bytes", **written}
    assert written["precision"] is None

    code, stdout, err = run_cli(["check", small_rsnn_checkpoint, "--target", "toy", "--data", toy_data, "--json",
                                 "--time-steps", "30"], capsys)
    assert code == 0, err
    record = json.loads(stdout)
    artefact = record.pop("artefact")
    assert artefact["sha256"] == sha and artefact["compiled_by_check"] and artefact["target"] == "toy"
    assert record.pop("input_layout") is None
    # the written toy artefact, found by the toy target's own identify: the same figures
    code, stdout, err = run_cli(["check", small_rsnn_checkpoint, "--artefact", out, "--data", toy_data, "--json"],
                                capsys)
    assert code == 0, err
    again = json.loads(stdout)
    assert again.pop("artefact")["sha256"] == sha and again.pop("input_layout") is None and again == record
    # the same accuracy as the IR reference computed here, independently of the toy target
    from snncc.frontends import load_model
    from snncc.ir.simulate import simulate

    with np.load(toy_data) as z:
        x, y = z["inputs"], z["labels"]
    expected = float(np.mean(np.asarray(simulate(load_model(small_rsnn_checkpoint), x.astype(np.float32)).prediction) == y))
    assert record == {"target": "toy", "samples": 6, "accuracy": expected, "precision": None}
    code, stdout, _ = run_cli(["check", small_rsnn_checkpoint, "--target", "toy", "--data", toy_data], capsys)
    assert code == 0 and "\ntoy check: 6 samples, accuracy" in stdout and stdout.startswith("measured artefact: toy")
    code, _, err = run_cli(["check", small_rsnn_checkpoint, "--artefact", out, "--target", "loihi", "--data", toy_data],
                           capsys)
    assert code == 2 and err == ("snncc: error: snncc check: --target: the artefact is a toy artefact, not loihi's "
                                 "(its target follows from the artefact; leave --target out)\n")


def test_a_capability_the_target_lacks_is_refused_in_one_line(toy, toy_data, small_rsnn_checkpoint, tmp_path, capsys):
    out = tmp_path / "m.toy"
    assert run_cli(["compile", small_rsnn_checkpoint, "-t", "toy", "-o", out], capsys)[0] == 0
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((30, 48), np.uint8))
    for args, verb in ((["map", out], "map"), (["emulate", out, "-i", x, "-o", tmp_path / "o.npz"], "emulate"),
                       (["report", out, "--energy"], "estimate"), (["run", out, "-i", x], "run"),
                       (["bench", out], "bench")):
        code, stdout, err = run_cli([*args, "--target", "toy"], capsys)
        assert code == 2 and stdout == ""
        assert err == (f"snncc: error: {out}: artefact: is a toy artefact; the toy target has no {verb} "
                       "(`snncc check MODEL --artefact --data D` measures it)\n")
    assert not (tmp_path / "o.npz").exists()
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "toy", "-o", out, "--scale", "global"], capsys)
    assert code == 2 and err == ("snncc: error: snncc compile: --scale: does not apply to --target toy (it takes "
                                 "--time-steps, --toy-precision)\n")
    code, _, err = run_cli(["check", small_rsnn_checkpoint, "-t", "toy"], capsys)   # no labels: agreement
    assert code == 2 and err == ("snncc: error: snncc check: --target: target 'toy' has no agreement without labels "
                                 "(capability 'agree'); give --data with labels\n")


def test_the_toy_target_through_the_installed_command(tmp_path, small_rsnn_checkpoint):
    """A fresh interpreter that finds the target only through PYTHONPATH's dist-info."""
    root = tmp_path / "site"
    root.mkdir()
    install_toy(root)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")]))
    out = tmp_path / "m.toy"
    proc = subprocess.run([sys.executable, "-m", "snncc.cli.main", "compile", str(small_rsnn_checkpoint), "-t", "toy",
                           "-o", str(out)], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    sha = hashlib.sha256(out.read_bytes()).hexdigest()
    assert proc.stdout.splitlines()[-1] == f"wrote {out} (SHA-256 {sha})" and json.loads(out.read_text())["nodes"] >= 3
    proc = subprocess.run([sys.executable, "-m", "snncc.cli.main", "compile", str(small_rsnn_checkpoint), "-t", "toy",
                           "-o", str(out), "--toy-precision", "6"], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(out.read_text())["precision"] == 6
    proc = subprocess.run([sys.executable, "-m", "snncc.cli.main", "compile", "--help"], capture_output=True, text=True,
                          env=dict(env, COLUMNS="200"), timeout=300)
    assert proc.returncode == 0 and "--toy-precision" in proc.stdout and "(--target toy)" in proc.stdout


# -- the toy's own option ---------------------------------------------------------------------------
def test_the_toy_option_is_offered_with_help_naming_its_target(toy, capsys):
    offers = {o.name: o for o in offered_options(["lower"])}
    assert offers["toy_precision"].targets == ("toy",) and offers["toy_precision"].kind is int
    assert offers["toy_precision"].help == "Bits of the toy's weights (2..16). (--target toy)"
    assert offers["time_steps"].targets == ("c", "jetson", "loihi", "toy", "xylo")  # one flag, five targets
    assert all(f"--target {t}:" in offers["time_steps"].help for t in ("c", "jetson", "loihi", "toy", "xylo"))
    assert offers["allow_reset_change"].targets == ("loihi", "xylo")          # Loihi's and Xylo's switch
    assert "toy_precision" in {o.name for o in offered_options(["check", "agree"])}
    assert "toy_precision" not in {o.name for o in offered_options(["map"])}
    assert "toy_precision" in {o.name for o in offered_options(["map", "lower"])}   # snncc map MODEL compiles
    for verb, shown in (("compile", True), ("check", True), ("emulate", False)):
        code, stdout, _ = run_cli([verb, "--help"], capsys)
        assert code == 0 and ("--toy-precision" in stdout) == shown, verb


def test_the_toy_option_is_validated_by_the_toy_and_reaches_lower_and_check(toy, toy_data, small_rsnn_checkpoint,
                                                                            tmp_path, capsys):
    out = tmp_path / "m.toy"
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "toy", "-o", out, "--toy-precision", "8"], capsys)
    assert code == 0, err
    assert json.loads(out.read_text())["precision"] == 8
    bad = tmp_path / "bad.toy"
    code, stdout, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "toy", "-o", bad, "--toy-precision", "1"],
                                capsys)
    assert (code, stdout) == (2, "") and not bad.exists()
    assert err == "snncc: error: snncc compile: --toy-precision: precision must be a whole number in [2, 16], got 1\n"
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", tmp_path / "m.net",
                            "--toy-precision", "8"], capsys)
    assert code == 2 and err == ("snncc: error: snncc compile: --toy-precision: does not apply to --target loihi (it "
                                 "takes --timing, --scale, --replicas, --allow-reset-change, --time-steps)\n")
    code, stdout, err = run_cli(["check", small_rsnn_checkpoint, "-t", "toy", "--data", toy_data, "--toy-precision",
                                 "4", "--json"], capsys)
    assert code == 0, err
    assert json.loads(stdout)["precision"] == 4


def test_the_toy_option_from_the_api(toy, toy_data, small_rsnn_checkpoint, tmp_path):
    out = tmp_path / "m.toy"
    record = api.compile(small_rsnn_checkpoint, target="toy", output=out, toy_precision=12, time_steps=30)
    assert record.as_dict()["precision"] == 12 and json.loads(out.read_text())["time_steps"] == 30
    assert api.check(small_rsnn_checkpoint, target="toy", data=toy_data, toy_precision=5).as_dict()["precision"] == 5
    with pytest.raises(SnnccError) as err:
        api.compile(small_rsnn_checkpoint, target="toy", output=out, toy_precision=17)
    assert err.value.line() == "--toy-precision: precision must be a whole number in [2, 16], got 17"
    with pytest.raises(SnnccError) as err:
        api.compile(small_rsnn_checkpoint, target="ir", output=tmp_path / "m.snnir", toy_precision=8)
    assert err.value.line() == "--toy-precision: does not apply to --target ir (it takes no target options)"
    with pytest.raises(TypeError):          # an option no installed target declares is a bug, as in Python
        api.compile(small_rsnn_checkpoint, target="toy", output=out, toy_colour="red")


# -- option records --------------------------------------------------------------------------------
@pytest.mark.parametrize("name, given, line", [
    ("ir", {"time_steps": 5}, "--time-steps: does not apply to --target ir (it takes no target options)"),
    ("ir", {"scale": "global"}, "--scale: does not apply to --target ir (it takes no target options)"),
    ("loihi", {"jetpack": "5.1"}, "--jetpack: does not apply to --target loihi (it takes --timing, --scale, "
                                  "--replicas, --allow-reset-change, --stream, --time-steps)"),
    ("jetson", {"timing": "paper"}, "--timing: does not apply to --target jetson (it takes --jetpack, --time-steps)"),
    ("jetson", {"stream": True}, "--stream: does not apply to --target jetson (it takes --jetpack, --time-steps)"),
])
def test_an_option_the_target_does_not_take_is_refused(name, given, line):
    with pytest.raises(SnnccError) as err:
        target_options(get_target(name), given)
    assert err.value.line() == line


def test_option_records_are_built_from_the_given_values():
    """(``snncc.targets.target_options``: the registry's, which knows every installed target's options.)"""
    loihi, jetson = get_target("loihi"), get_target("jetson")
    assert target_options(loihi, {"scale": "global", "timing": None, "source": "m.pt"}) == LoihiOptions(
        scale="global", source="m.pt")
    assert target_options(jetson, {"jetpack": "6.1", "allow_reset_change": False, "stream": None}) == JetsonOptions(
        jetpack="6.1")
    assert target_options(get_target("ir"), None) == IROptions()
    given = LoihiOptions(stream=True)
    assert target_options(loihi, given) is given
    with pytest.raises(TypeError):          # a key that is no option at all is a bug, not a user error
        target_options(loihi, {"progress": print})
    with pytest.raises(Exception):          # records are frozen
        given.stream = False


def test_capability_returns_the_bound_method_or_refuses():
    loihi = get_target("loihi")
    assert capability(loihi, "check") == loihi.check
    with pytest.raises(SnnccError) as err:
        capability(get_target("ir"), "check")
    assert err.value.line() == "--target: target 'ir' has no check in this snncc"
    with pytest.raises(ValueError):
        capability(loihi, "fly")


def test_a_plug_in_that_does_not_load_is_refused_when_chosen_and_hides_no_other_flag(tmp_path, monkeypatch, capsys,
                                                                                     small_rsnn_checkpoint):
    root = tmp_path / "site"
    root.mkdir()
    (root / "snncc_broken.py").write_text("raise ImportError('needs the vendor SDK')\n")
    info = root / "snncc_broken-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: snncc-broken\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[snncc.targets]\nbroken = snncc_broken:target\n")
    monkeypatch.syspath_prepend(str(root))
    code, stdout, _ = run_cli(["compile", "--help"], capsys)
    assert code == 0 and "--scale" in stdout and "--jetpack" in stdout
    code, stdout, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "broken", "-o", tmp_path / "m.x"], capsys)
    assert (code, stdout) == (2, "") and not (tmp_path / "m.x").exists()
    assert err == ("snncc: error: snncc compile: --target: target 'broken' is installed but does not load "
                   "(snncc_broken:target): ImportError: needs the vendor SDK\n")
