"""snncc check --target jetson measures the written artefact directory: label-free agreement too,
the directory's stated hash, and inputs of another length through the step model."""

from __future__ import annotations

import hashlib
import json

import numpy as np

from snncc.targets.jetson.written import artefact_files
from snncc_test_helpers import run_cli


def _json(capsys, args):
    code, out, err = run_cli(args, capsys)
    assert code == 0, err
    return json.loads(out)


def test_jetson_agreement_without_labels_on_the_written_directory(tmp_path, capsys, short_rsnn_checkpoint):
    out = tmp_path / "j"
    report = _json(capsys, ["compile", short_rsnn_checkpoint, "--target", "jetson", "-o", out, "--json"])
    manifest = json.loads((out / "manifest.json").read_text())
    names = artefact_files(manifest)
    assert names == ["build_engine.sh", "manifest.json", "model.onnx", "run.py", "step.onnx"]
    lines = "".join(f"{hashlib.sha256((out / n).read_bytes()).hexdigest()}  {n}\n" for n in names)
    assert report["sha256"] == hashlib.sha256(lines.encode()).hexdigest()
    (out / "model.plan").write_bytes(b"an engine built on the board is not part of the artefact")
    here = _json(capsys, ["check", short_rsnn_checkpoint, "--target", "jetson", "--limit", "6", "--json"])
    written = _json(capsys, ["check", short_rsnn_checkpoint, "--artefact", out, "--limit", "6", "--json"])
    assert here.pop("artefact")["sha256"] == written.pop("artefact")["sha256"] == report["sha256"]
    assert here == written
    assert written["samples"] == 6 and written["steps"] == manifest["time_steps"] and written["target"] == "jetson"
    a = written["argmax"]
    assert a["decided"] + a["ties"] + a["silent"] == 6 and written["argmax_agreement"] == a["share"]
    assert set(written["liveness"]["float"]) == {"hidden", "out"} and set(written["liveness"]["jetson"]) == {"out"}
    assert written["details"]["runtime"].startswith("model.onnx")
    assert written["possible"] == ["other"] and written["causes"]["reset"] is None          # "—" on this target


def test_data_of_another_length_run_through_the_step_model(tmp_path, capsys, short_rsnn_checkpoint):
    out = tmp_path / "j"
    _json(capsys, ["compile", short_rsnn_checkpoint, "--target", "jetson", "-o", out, "--json"])
    steps = json.loads((out / "manifest.json").read_text())["time_steps"]
    rng = np.random.default_rng(0)
    np.savez(tmp_path / "d.npz", inputs=(rng.random((4, 17, 24)) < 0.2).astype(np.uint8),
             labels=rng.integers(0, 28, 4))
    rec = _json(capsys, ["check", short_rsnn_checkpoint, "--artefact", out, "--data", tmp_path / "d.npz", "--json"])
    assert steps != 17 and rec["steps"] == 17 and rec["details"]["runtime"].startswith("step.onnx")
    assert any("step model ran them one step at a time" in n for n in rec["notes"])
    assert rec["details"]["spike_agreement"] == 1.0 and rec["accuracy"]["artefact"] == rec["accuracy"]["float"]
