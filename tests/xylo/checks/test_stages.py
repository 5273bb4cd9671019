"""``snncc check --target xylo``: the written artefact against the float model, loss broken down by cause."""

import json
from pathlib import Path

import numpy as np
import pytest

from snncc.frontends import LoadOptions, load_model
from snncc.targets.xylo.checks.stages import STAGES, check_written, deployed_graph, float_counts, rounded_decays
from snncc.targets.xylo.artefact.read import read_artefact
from snncc_test_helpers import run_cli

BRAILLE = Path(__file__).resolve().parents[2] / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
ZERO = ["--dt", "1e-4", "--reset", "zero", "--allow-reset-change"]


def test_check_without_labels_breaks_the_loss_down_by_cause(tmp_path, capsys):
    """The subtract-reset Braille graph read with reset to zero: the reset change is a cause of its own."""
    code, out, err = run_cli(["check", BRAILLE, "--target", "xylo", "--rule", "direct", *ZERO, "--samples", "80",
                              "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert [s["name"] for s in d["stages"]] == list(STAGES)
    causes = [row["cause"] for row in d["losses"]]
    assert causes == ["reset change", "decay rounding", "weight quantization and the rule's placement",
                      "multi-spike clipping (31 events per hidden neuron and step)",
                      "integer arithmetic (16-bit saturation, state rounding)"]
    stage = {s["name"]: s for s in d["stages"]}
    assert stage["deployed"]["agreement"]["agreement"] < 1.0          # resetting by subtraction changes decisions
    assert d["losses"][0]["agreement_points"] == pytest.approx(100 * (1 - stage["deployed"]["agreement"]["agreement"]))
    assert d["losses"][4]["agreement_points"] == pytest.approx(
        100 * (stage["twin"]["agreement"]["agreement"] - stage["chip"]["agreement"]["agreement"]))
    assert d["events"]["samples"] == 8 and d["events"]["hidden_capped"] >= 0
    assert "SYNTHETIC" in d["inputs"] and d["ceiling"]["noise"] == 0.01
    assert "reset zero -> subtract" in d["notes"][0]


def test_check_with_labels_measures_a_written_artefact(tmp_path, capsys):
    art = tmp_path / "b.xylo"
    code, _, err = run_cli(["compile", BRAILLE, "-o", art, "--rule", "direct", *ZERO, "--calibration-samples", "16",
                            "--time-steps", "64"], capsys)
    assert code == 0, err
    g = load_model(BRAILLE, LoadOptions(dt=1e-4, reset="zero"))
    x = (np.random.default_rng(3).random((24, 64, 12)) < 0.08).astype(np.uint8)
    labels = np.argmax(float_counts(g, x), axis=1)             # labels = the float model's own decisions
    written = read_artefact(art)
    rec = check_written(g, written, x, labels, "24 test samples").as_dict()
    acc = {s["name"]: s["accuracy"] for s in rec["stages"]}
    assert acc["trained"] == 1.0 and 0.0 <= acc["chip"] <= 1.0
    assert rec["losses"][0]["accuracy_points"] == pytest.approx(100 * (1.0 - acc["deployed"]))
    # the stages are the runs they claim: the deployed graph resets by subtraction, the decays graph is on the grid
    dep = deployed_graph(g, written.manifest)
    assert all(op.reset == "subtract" for _, op in dep.items() if hasattr(op, "reset"))
    from snncc.ir.nodes import LIF
    from snncc.targets.xylo.lowering import decays as kernels
    for _, op in rounded_decays(dep).items():
        if isinstance(op, LIF):
            a, b = op.decays(dep.dt)
            assert np.allclose(a, kernels.grid(kernels.nearest_dash(a))) and np.allclose(b, kernels.grid(kernels.nearest_dash(b)))


def test_check_measures_the_artefact_given_and_names_its_hash(tmp_path, capsys):
    """--artefact: the Xylo target recognises its directory (identify), the hash is compile's, and an artefact
    compiled from another model is refused in one line."""
    from snncc.ir.serialize import save_graph

    from xylo_models import chain

    model, other = tmp_path / "a.snnir", tmp_path / "b.snnir"
    save_graph(chain(np.random.default_rng(0)), model)
    save_graph(chain(np.random.default_rng(1)), other)
    art = tmp_path / "a.xylo"
    code, out, err = run_cli(["compile", model, "-o", art, "--rule", "direct", "--calibration-samples", "12",
                              "--time-steps", "48", "--json"], capsys)
    assert code == 0, err
    sha = json.loads(out)["sha256"]
    code, out, err = run_cli(["check", model, "--artefact", art, "--samples", "30", "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["artefact"]["target"] == "xylo" and d["artefact"]["sha256"] == sha and not d["artefact"]["compiled_by_check"]
    assert [s["name"] for s in d["stages"]] == list(STAGES)
    code, _, err = run_cli(["check", other, "--artefact", art, "--samples", "30"], capsys)
    assert code == 2 and "was compiled from another model" in err and len(err.strip().splitlines()) == 1


def test_check_reports_liveness_in_float_and_on_the_chip(capsys):
    code, out, err = run_cli(["check", BRAILLE, "--target", "xylo", "--rule", "direct", "--dt", "1e-4", "--reset",
                              "subtract", "--samples", "20", "--calibration-samples", "16", "--time-steps", "64",
                              "--json"], capsys)
    assert code == 0, err
    live = json.loads(out)["liveness"]
    assert set(live) == {"float (deployed)", "chip"} and set(live["chip"]) == {"hidden (chip)", "output (chip)"}
    assert live["chip"]["hidden (chip)"]["neurons"] == 40 and live["chip"]["output (chip)"]["spikes"] > 0
    assert all(a["status"] in ("active", "silent", "saturated") for a in live["float (deployed)"].values())
