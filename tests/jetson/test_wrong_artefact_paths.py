"""An artefact of one target given to another target's command: the refusal names what it is and
which command reads it (not 'file does not exist')."""

from __future__ import annotations

import numpy as np

from snncc_test_helpers import run_cli
from tests.loihi.helpers import small_graph


def _bundle(tmp_path):
    from snncc.targets.loihi import target

    path = tmp_path / "b.net"
    target.lower(small_graph(seed=1), {"scale": "global"}).write(path)
    return path


def test_emulate_map_report_inspect_of_a_jetson_artefact_say_what_it_is(artefacts, tmp_path, capsys):
    jetson_dir = artefacts["rsnn"][2]
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((2, 30, 6), np.uint8))
    for args in (["emulate", jetson_dir, "-i", x, "-o", tmp_path / "o.npz"], ["map", jetson_dir],
                 ["report", jetson_dir, "--energy"], ["inspect", jetson_dir], ["compile", jetson_dir, "-o", tmp_path / "c.net"]):
        code, _, err = run_cli(args, capsys)
        assert code == 2, args
        (line,) = err.strip().splitlines()
        assert line.startswith(f"snncc: error: {jetson_dir}: ") and "does not exist" not in line, line
        assert "is a Jetson artefact (a directory)" in line and "`snncc run` runs it" in line, line
        assert ", not a model file" in line or ", not a Loihi bundle" in line, line
    assert not (tmp_path / "o.npz").exists() and not (tmp_path / "c.net").exists()


def test_run_and_bench_of_a_loihi_bundle_say_what_it_is(tmp_path, capsys):
    bundle = _bundle(tmp_path)
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((2, 30, 8), np.uint8))
    for args in (["run", bundle, "-i", x], ["bench", bundle, "--samples", "2"]):
        code, _, err = run_cli(args, capsys)
        assert code == 2, args
        (line,) = err.strip().splitlines()
        assert "is a Loihi bundle (.net, an HDF5 file), not a Jetson artefact" in line, line
        assert "`snncc emulate` runs it" in line, line


def test_missing_paths_and_plain_directories_are_still_named_so(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    x = tmp_path / "x.npy"
    np.save(x, np.zeros((2, 30, 8), np.uint8))
    code, _, err = run_cli(["emulate", tmp_path / "none.net", "-i", x, "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and err.strip().endswith("none.net: path: file does not exist")
    code, _, err = run_cli(["emulate", tmp_path / "empty", "-i", x, "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and err.strip().endswith("empty: path: is a directory, not a Loihi bundle (.net, an HDF5 file)")
    code, _, err = run_cli(["run", tmp_path / "none", "-i", x], capsys)
    assert code == 2 and err.strip().endswith("none: path: does not exist")
