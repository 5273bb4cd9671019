"""``snncc check --target xylo``: the written artefact against the float model, loss broken down by cause
(``kit.checks.CheckReport``), agreement undefined over silence, memory bounded by chunks."""

import json
from pathlib import Path

import numpy as np
import pytest

from snncc.frontends import LoadOptions, load_model
from snncc.ir.serialize import save_graph
from snncc.targets.xylo.artefact.read import read_artefact
from snncc.targets.xylo.checks.stages import (STAGES, check_written, deployed_graph, float_counts, random_chunks,
                                             rounded_decays)
from snncc_test_helpers import run_cli

from xylo_models import chain

BRAILLE = Path(__file__).resolve().parents[2] / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
ZERO = ["--dt", "1e-4", "--reset", "zero", "--allow-reset-change"]
KEYS = [key for key, _, _ in STAGES]


def test_check_without_labels_breaks_the_loss_down_by_cause(capsys):
    """The subtract-reset Braille graph read with reset to zero: the reset change is a cause of its own."""
    code, out, err = run_cli(["check", BRAILLE, "--target", "xylo", "--rule", "direct", *ZERO, "--samples", "80",
                              "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["target"] == "xylo" and [s["key"] for s in d["stages"]] == KEYS
    assert [s["cause"] for s in d["stages"]] == [None, "reset", "decays", "weights", "saturation", "saturation"]
    assert d["possible"] == ["reset", "weights", "decays", "saturation"]
    share = {s["key"]: s["agreement"]["share"] for s in d["stages"]}
    assert share["trained"] == 1.0 and share["deployed"] < 1.0          # resetting by subtraction changes decisions
    assert d["causes"]["reset"] == pytest.approx(100 * (1 - share["deployed"]))
    assert d["causes"]["saturation"] == pytest.approx(100 * (share["uncapped"] - share["chip"]))
    assert d["causes"]["timing"] is None and d["causes"]["other"] is None
    assert d["argmax_agreement"] == share["chip"] and d["total_points"] == pytest.approx(100 * (1 - share["chip"]))
    assert d["details"]["rule_events"]["samples"] == 8 and d["details"]["rule_events"]["hidden_capped"] >= 0
    assert "SYNTHETIC" in d["inputs"] and d["ceiling"]["noise"] == 0.01 and d["samples"] == 80
    assert "reset zero -> subtract" in d["notes"][0] and any("attributed to saturation" in n for n in d["notes"])


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
    acc = {s["key"]: s["accuracy"] for s in rec["stages"]}
    assert acc["trained"] == 1.0 and 0.0 <= acc["chip"] <= 1.0 and rec["accuracy"]["float"] == 1.0
    assert rec["accuracy"]["artefact"] == acc["chip"]
    # the stages are the runs they claim: the deployed graph resets by subtraction, the decays graph is on the grid
    dep = deployed_graph(g, written.manifest)
    assert all(op.reset == "subtract" for _, op in dep.items() if hasattr(op, "reset"))
    from snncc.ir.nodes import LIF
    from snncc.targets.xylo.lowering.decays import grid, nearest_dash
    for _, op in rounded_decays(dep).items():
        if isinstance(op, LIF):
            a, b = op.decays(dep.dt)
            assert np.allclose(a, grid(nearest_dash(a))) and np.allclose(b, grid(nearest_dash(b)))


def test_chunks_give_the_figures_of_one_run(tmp_path, capsys):
    """The chunked check equals itself run on the same inputs at once, and the random inputs drawn chunk by chunk
    are the kit's random inputs."""
    from snncc.targets.kit.agreement import random_inputs
    from snncc.targets.xylo.checks import stages

    x = random_inputs(70, 40, 12, 0.08, 0)
    assert np.array_equal(np.concatenate(list(random_chunks(70, 40, 12, 0.08, 0, 16))), x)
    art = tmp_path / "c.xylo"
    code, _, err = run_cli(["compile", BRAILLE, "-o", art, "--rule", "direct", *ZERO, "--calibration-samples", "8",
                            "--time-steps", "40"], capsys)
    assert code == 0, err
    g = load_model(BRAILLE, LoadOptions(dt=1e-4, reset="zero"))
    written = read_artefact(art)
    whole = check_written(g, written, x, None, "x", noise=0.01).as_dict()
    saved = stages.CHUNK
    stages.CHUNK = 16
    try:
        parts = check_written(g, written, None, None, "x", noise=0.01, random=(70, 40, 0.08, 0)).as_dict()
    finally:
        stages.CHUNK = saved
    assert parts["stages"] == whole["stages"] and parts["ceiling"] == whole["ceiling"]
    assert parts["liveness"] == whole["liveness"] and parts["details"] == whole["details"]


def test_check_measures_the_artefact_given_and_names_its_hash(tmp_path, capsys):
    """--artefact: the Xylo target recognises its directory (identify), the hash is compile's, and an artefact
    compiled from another model is refused in one line."""
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
    assert [s["key"] for s in d["stages"]] == KEYS
    code, _, err = run_cli(["check", other, "--artefact", art, "--samples", "30"], capsys)
    assert code == 2 and "was compiled from another model" in err and len(err.strip().splitlines()) == 1


def test_check_reports_liveness_in_float_and_on_the_chip(capsys):
    code, out, err = run_cli(["check", BRAILLE, "--target", "xylo", "--rule", "direct", "--dt", "1e-4", "--reset",
                              "subtract", "--samples", "20", "--calibration-samples", "16", "--time-steps", "64",
                              "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    live = d["liveness"]
    assert set(live) == {"float", "chip"} and set(live["chip"]) == {"hidden (chip)", "output (chip)"}
    assert live["chip"]["hidden (chip)"]["neurons"] == 40 and live["chip"]["output (chip)"]["spikes"] > 0
    assert all(a["status"] in ("active", "silent", "saturated") for a in live["float"].values())
    assert "/tmp" not in " ".join(d["detail_lines"] if "detail_lines" in d else []) and "snncc-measure" not in out


def test_a_silent_model_has_undefined_agreement_and_its_silent_populations_named(tmp_path, capsys):
    """A model that never spikes: agreement undefined (JSON null), never 0 % or a correlation of 1, and the silent
    populations named in float and on the chip."""
    g = chain(np.random.default_rng(0))
    g.node("w_in").weight = g.node("w_in").weight * 0 - 1.0          # inhibition only: nothing ever spikes
    model = tmp_path / "silent.snnir"
    save_graph(g, model)
    art = tmp_path / "silent.xylo"
    code, _, err = run_cli(["compile", model, "-o", art, "--rule", "single", "--calibration-samples", "12",
                            "--time-steps", "48"], capsys)
    assert code == 0, err
    code, out, err = run_cli(["check", model, "--artefact", art, "--samples", "30", "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["argmax_agreement"] is None and d["count_correlation"] is None and d["argmax"]["silent"] == 30
    assert all(s["agreement"]["share"] is None for s in d["stages"]) and d["total_points"] is None
    flagged = " ".join(d["flagged"])
    assert "population 'hidden' never spikes in float" in flagged and "population 'out' never spikes in float" in flagged
    assert "never spikes on the chip" in flagged
    code, text, err = run_cli(["check", model, "--artefact", art, "--samples", "30"], capsys)
    assert code == 0 and "argmax agreement   undefined: outputs silent" in text
