"""The Xylo artefact's identity: ``identify`` reads the manifest only and returns the model record the artefact
wrote (``kit.artefact.model_record``: graph fingerprint, dt, resets) as ``identity.model``."""

from __future__ import annotations

import json

import numpy as np

from snncc.frontends import load_model
from snncc.ir.serialize import save_graph
from snncc.targets.kit.artefact import model_record
from snncc.targets.xylo.capabilities import target
from snncc_test_helpers import run_cli

from xylo_models import chain


def test_identify_returns_the_model_record_the_manifest_holds(tmp_path, capsys):
    model = tmp_path / "m.snnir"
    save_graph(chain(np.random.default_rng(0)), model)
    art = tmp_path / "m.xylo"
    code, _, err = run_cli(["compile", model, "-o", art, "--rule", "direct", "--calibration-samples", "8",
                            "--time-steps", "32"], capsys)
    assert code == 0, err
    manifest = json.loads((art / "manifest.json").read_text())
    assert manifest["model"] == model_record(load_model(model))          # the model as compile and check load it
    identity = target.identify(art)
    assert identity.target == "xylo" and identity.model == manifest["model"]
    assert identity.files == ["README.md", "manifest.json", "run_on_board.py", "spec.npz"]
    assert identity.source_sha256 == manifest["source"]["sha256"]
    older = dict(manifest)
    older.pop("model")
    (art / "manifest.json").write_text(json.dumps(older))
    assert target.identify(art).model is None          # an artefact of an older snncc records none
    assert target.identify(tmp_path) is None
