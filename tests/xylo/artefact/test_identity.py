"""The Xylo artefact's identity: ``identify`` reads the manifest only and returns the model record the artefact
wrote (``kit.artefact.model_record``: graph fingerprint, dt, resets) as ``identity.model``."""

from __future__ import annotations

import json

from snncc.frontends import load_model
from snncc.targets.kit.artefact import model_record
from snncc.targets.xylo.capabilities import target


def test_identify_returns_the_model_record_the_manifest_holds(compiled, tmp_path):
    import shutil

    model, written, _ = compiled
    art = tmp_path / "m.xylo"
    shutil.copytree(written, art)
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
