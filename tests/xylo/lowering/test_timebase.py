"""One time base (issue 39): a sample lasts ``kit.timebase.sample_steps(graph, --time-steps)`` steps in the Xylo
lowering's calibration, in check's and report's random samples (the artefact records it) and in fine-tuning
(``finetune/test_finetune_target.py``)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from snncc.frontends import LoadOptions, load_model
from snncc.targets.kit.timebase import sample_steps
from snncc_test_helpers import run_cli

NIR = Path(__file__).resolve().parents[2] / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
MODEL = ["--dt", "1e-4", "--reset", "subtract"]


@pytest.mark.parametrize("given", [None, 48])
def test_calibration_check_and_report_use_the_models_time_base(tmp_path, capsys, given):
    graph = load_model(NIR, LoadOptions(dt=1e-4, reset="subtract"))
    steps, rule = sample_steps(graph, given)
    art = tmp_path / "t.xylo"
    flags = [] if given is None else ["--time-steps", str(given)]
    code, _, err = run_cli(["compile", NIR, *MODEL, "--rule", "direct", "--calibration-samples", "4", *flags,
                            "-o", art], capsys)
    assert code == 0, err
    manifest = json.loads((art / "manifest.json").read_text())
    assert manifest["feed"]["sample_steps"] == steps and manifest["feed"]["sample_steps_rule"] == rule
    assert f"{steps} steps" in manifest["quantization"]["calibration"]["inputs"]
    code, out, err = run_cli(["check", NIR, *MODEL, "--artefact", art, "--samples", "12", "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["steps"] == steps and f"{steps} steps" in d["inputs"]
    code, out, err = run_cli(["report", art, "--energy", "--samples", "3", "--json"], capsys)
    assert code == 0, err
    assert f"of {steps} steps" in json.loads(out)["rates_from"]
