"""Edited replicated bundles (a user's probe): each command ends in one line ``snncc: error: <file>: <field>: <rule>``
and exit status 2, never a traceback, a wrong answer or a map of a network the model is not."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from snncc_test_helpers import run_cli

GRAPH = Path(__file__).resolve().parents[2] / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
MODEL = [str(GRAPH), "--dt", "1e-4", "--reset", "subtract"]


@pytest.fixture(scope="module")
def replicated(tmp_path_factory) -> Path:
    """``snncc compile braille_noDelay_noBias_subtract.nir --dt 1e-4 --reset subtract --allow-reset-change
    --replicas 2 -o r2.net`` (module-scoped: every probe edits a copy)."""
    from snncc.cli.main import run

    out = tmp_path_factory.mktemp("hostile") / "r2.net"
    assert run(["compile", *MODEL, "--allow-reset-change", "--replicas", "2", "--time-steps", "40",
                "-o", str(out)]) == 0
    return out


def _copy(replicated: Path, tmp_path: Path, name: str) -> Path:
    path = tmp_path / name
    shutil.copy(replicated, path)
    return path


def _metadata(path: Path, **changes) -> None:
    with h5py.File(path, "r+") as f:
        meta = json.loads(f["snncc/metadata"][0])
        meta.update(changes)
        del f["snncc/metadata"]
        f["snncc"].create_dataset("metadata", data=[json.dumps(meta).encode()])


def _last_layer_deleted(path: Path) -> None:
    with h5py.File(path, "r+") as f:
        del f[f"layer/{len(f['layer']) - 1}"]


def _one_line(capsys, args: list, file: Path, field: str, words: str) -> None:
    code, _, err = run_cli(args, capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"snncc: error: {file}: {field}: ") and words in lines[0], lines[0]


def test_replication_metadata_of_the_wrong_kind_is_one_line_in_check(replicated, tmp_path, capsys):
    bad = _copy(replicated, tmp_path, "rep.net")
    _metadata(bad, replication=[1, 2])                     # was an AttributeError in check --artefact
    _one_line(capsys, ["check", *MODEL, "--artefact", bad, "--samples", "8"], bad, "/snncc/metadata",
              "replication must be a record")
    _metadata(bad, replication={"replicas": 2, "relay": "replica_relay", "populations": {"lif1.lif": [40, 90]}})
    _one_line(capsys, ["check", *MODEL, "--artefact", bad, "--samples", "8"], bad, "/snncc/metadata",
              "'lif1.lif' must map to [model size, size]")


def test_a_bundle_with_its_last_layer_deleted_is_one_line_in_check(replicated, tmp_path, capsys):
    bad = _copy(replicated, tmp_path, "cut.net")
    _last_layer_deleted(bad)                               # was a numpy broadcasting ValueError in check
    _one_line(capsys, ["check", *MODEL, "--artefact", bad, "--samples", "8"], bad, "/snncc/metadata",
              "layer_names lists 4 layers but /layer holds 3")


def test_a_replicated_bundle_missing_its_output_layer_is_neither_emulated_nor_mapped(replicated, tmp_path, capsys):
    bad = _copy(replicated, tmp_path, "cut.net")
    _last_layer_deleted(bad)                               # was emulated (predictions 37 of a 7-class model) and mapped
    x = tmp_path / "x.npy"
    np.save(x, (np.random.default_rng(0).random((3, 40, 12)) < 0.1).astype(np.uint8))
    out = tmp_path / "o.npz"
    _one_line(capsys, ["emulate", bad, "-i", x, "-o", out], bad, "/snncc/metadata", "a layer was removed")
    _one_line(capsys, ["map", bad], bad, "/snncc/metadata", "a layer was removed")
    _one_line(capsys, ["report", bad, "--energy", "--samples", "2"], bad, "/snncc/metadata", "a layer was removed")
    assert not out.exists()


def test_recorded_options_a_compile_would_refuse_are_one_line_in_check(replicated, tmp_path, capsys):
    bad = _copy(replicated, tmp_path, "opts.net")
    _metadata(bad, compile_options={"scale": "bogus", "timing": "exact", "replicas": 2, "allow_reset_change": True,
                                    "time_steps": 40})
    _one_line(capsys, ["check", *MODEL, "--artefact", bad, "--samples", "8"], bad, "/snncc/metadata",
              "compile_options: --scale: scale must be one of")


def test_the_untouched_bundle_is_checked_emulated_and_mapped(replicated, tmp_path, capsys):
    x = tmp_path / "x.npy"
    np.save(x, (np.random.default_rng(0).random((3, 40, 12)) < 0.1).astype(np.uint8))
    for args in (["check", *MODEL, "--artefact", replicated, "--samples", "8"],
                 ["emulate", replicated, "-i", x, "-o", tmp_path / "o.npz"], ["map", replicated]):
        code, _, err = run_cli(args, capsys)
        assert code == 0, (args, err)
    assert int(np.load(tmp_path / "o.npz")["prediction"].max()) < 7      # a 7-class model's predictions
