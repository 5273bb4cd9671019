"""An artefact given to a command its target does not offer, or where a model file is expected: the refusal names
which target's artefact it is and which commands read it (the core asks every target's ``identify``; it names
no target itself)."""

from __future__ import annotations

import numpy as np

from snncc_test_helpers import run_cli
from tests.loihi.helpers import small_graph


def _bundle(tmp_path):
    from snncc.targets.loihi import target

    path = tmp_path / "b.net"
    target.lower(small_graph(seed=1), {"scale": "global"}).write(path)
    return path


def _line(args, capsys):
    code, _, err = run_cli(args, capsys)
    assert code == 2, args
    (line,) = err.strip().splitlines()
    return line


def test_emulate_map_report_inspect_of_a_jetson_artefact_say_what_it_is(artefacts, tmp_path, capsys):
    jetson_dir = artefacts["rsnn"][2]
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((2, 30, 6), np.uint8))
    for args, verb in ((["emulate", jetson_dir, "-i", x, "-o", tmp_path / "o.npz"], "emulate"), (["map", jetson_dir], "map"),
                       (["report", jetson_dir, "--energy"], "estimate")):
        line = _line(args, capsys)
        assert line == (f"snncc: error: {jetson_dir}: artefact: is a jetson artefact; the jetson target has no {verb} "
                        "(`snncc run` runs it, `snncc bench` times it, `snncc check MODEL --artefact` measures it)"), line
    for args in (["inspect", jetson_dir], ["compile", jetson_dir, "-o", tmp_path / "c.net"]):
        line = _line(args, capsys)
        assert line.startswith(f"snncc: error: {jetson_dir}: model: is Jetson artefact (ONNX opset"), line
        assert "(target jetson): `snncc run` runs it" in line and line.endswith("; it is not a model file"), line
    assert not (tmp_path / "o.npz").exists() and not (tmp_path / "c.net").exists()


def test_run_and_bench_of_a_loihi_bundle_say_what_it_is(tmp_path, capsys):
    bundle = _bundle(tmp_path)
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((2, 30, 8), np.uint8))
    for args, verb in ((["run", bundle, "-i", x], "run"), (["bench", bundle, "--samples", "2"], "bench")):
        line = _line(args, capsys)
        assert line.startswith(f"snncc: error: {bundle}: artefact: is a loihi artefact; the loihi target has no {verb} ("), line
        assert "`snncc emulate` runs it" in line, line


def test_missing_paths_and_plain_directories_are_still_named_so(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((2, 30, 8), np.uint8))
    line = _line(["emulate", tmp_path / "none.net", "-i", x, "-o", tmp_path / "o.npz"], capsys)
    assert line.endswith("none.net: artefact: file does not exist"), line
    line = _line(["emulate", tmp_path / "empty", "-i", x, "-o", tmp_path / "o.npz"], capsys)
    assert line.startswith(f"snncc: error: {tmp_path / 'empty'}: artefact: is not an artefact any installed target "
                           "recognises ("), line
    line = _line(["run", tmp_path / "none", "-i", x], capsys)
    assert line.endswith("none: artefact: file does not exist"), line
    line = _line(["inspect", tmp_path / "none.nir"], capsys)
    assert line.endswith("none.nir: model: file does not exist"), line
