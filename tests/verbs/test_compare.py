"""snncc compare: every row measured on the same inputs and time base by the target's own check (its agreement equals
``check --artefact`` of the same artefact on the same inputs), one row per target that can take the model and a
one-line reason for each that cannot, text / JSON / Markdown / figure from one record."""

from __future__ import annotations

import json

import numpy as np
import pytest

from snncc_test_helpers import run_cli

SUB = "braille_noDelay_noBias_subtract.nir"


@pytest.fixture(scope="module")
def compared(tmp_path_factory, shared_nir):
    from snncc.api import compare

    d = tmp_path_factory.mktemp("compare")
    record = compare(shared_nir / SUB, dt=1e-4, reset="subtract", targets="jetson,loihi,xylo", samples=40,
                     time_steps=40, allow_reset_change=True, calibration_samples=8, rule="single",
                     output=d / "t.md", figure=d / "f.png")
    return d, record


def test_rows_cover_every_target_on_the_same_inputs(compared):
    d, record = compared
    rows = {r.target: r for r in record.rows}
    assert record.samples == 40 and record.steps == 40
    assert {"float", "jetson", "loihi", "xylo"} <= set(rows) and any(r.kind == "ceiling" for r in record.rows)
    for name in ("jetson", "loihi", "xylo"):
        row = rows[name]
        assert row.error is None, row.error
        assert row.argmax.samples == 40 and row.sha256 and row.command.startswith("snncc compile ")
        assert set(row.causes) == {"reset", "weights", "decays", "saturation", "timing", "other"}
    assert rows["jetson"].causes["reset"] is None and "reset" not in rows["jetson"].possible   # "—" there
    assert rows["float"].neurobench.synaptic_operations["Dense"] > 0
    text = (d / "t.md").read_text()
    assert "| jetson |" in text and "NeuroBench 2.3" in text and (d / "f.png").stat().st_size > 1000
    data = json.loads(json.dumps(record.as_dict(), default=str))
    assert [r["target"] for r in data["rows"]][:1] == ["float"] and "argmax_agreement" in data["rows"][2]


def test_a_row_equals_check_of_the_same_artefact_on_the_same_inputs(compared, shared_nir, tmp_path, capsys):
    from snncc.api import check, compile as compile_model
    from snncc.measure.agreement import random_inputs

    _, record = compared
    jetson = next(r for r in record.rows if r.target == "jetson")
    compile_model(shared_nir / SUB, dt=1e-4, reset="subtract", target="jetson", output=tmp_path / "j", time_steps=40)
    x = random_inputs(40, 40, 12, 0.08, seed=0)
    np.savez(tmp_path / "x.npz", inputs=x)
    found = check(shared_nir / SUB, dt=1e-4, reset="subtract", artefact=tmp_path / "j", data=tmp_path / "x.npz",
                  agreement=True).as_dict()
    assert found["artefact"]["sha256"] == jetson.sha256
    assert found["argmax"] == jetson.argmax.as_dict() and found["argmax_agreement"] == jetson.argmax_agreement


def test_a_target_that_cannot_take_the_model_says_why_and_the_rest_go_on(shared_nir, capsys):
    code, stdout, err = run_cli(["compare", shared_nir / "braille_zero_2023.nir", "--dt", "1e-4", "--targets",
                                 "xylo,jetson", "--samples", "12", "--time-steps", "20", "--json"], capsys)
    assert code == 0, err
    rows = {r["target"]: r for r in json.loads(stdout)["rows"]}
    assert "--allow-reset-change" in rows["xylo"]["error"] and "\n" not in rows["xylo"]["error"]
    assert rows["jetson"]["error"] is None and rows["jetson"]["argmax"]["samples"] == 12
