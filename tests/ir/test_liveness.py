"""Float activity per population and the one-line warning for a model silent in float (snncc.ir.liveness).

Inputs are seeded random spike trains (SYNTHETIC); the graphs are the real ones in tests/data/nir.
"""

import json
from pathlib import Path

import numpy as np

from snncc.frontends import LoadOptions, load_model
from snncc.ir.liveness import (
    calibration_spikes, calibration_warning, population_activity, silence_warning, silent_population,
)
from snncc_test_helpers import run_cli

DATA = Path(__file__).resolve().parents[1] / "data" / "nir"


def _graph(name, dt):
    return load_model(DATA / name, LoadOptions(dt=dt))


def test_rates_per_population_of_a_live_trained_graph():
    g = _graph("braille_zero_2023.nir", 1e-4)
    x = calibration_spikes(12, 100)
    assert x.shape == (8, 100, 12) and x.dtype == np.uint8 and 0.03 < x.mean() < 0.07
    act = population_activity(g, x)
    assert set(act) == {"lif1.lif", "lif2"}
    hidden = act["lif1.lif"]
    assert hidden.neurons == 38 and 0.01 < hidden.rate < 0.2 and 0 <= hidden.silent_neurons < 38
    assert not hidden.silent and silent_population(g, act) is None
    assert calibration_warning(g, 100) is None


def test_a_silent_output_is_named_with_how_close_it_came():
    g = _graph("two_lif_neurons.nir", 1e-3)          # lif2: threshold 20 behind a 0.1 weight
    act = population_activity(g, calibration_spikes(1, 100))
    assert act["lif1"].rate > 0 and act["lif2"].silent and act["lif2"].silent_neurons == 1
    assert 0 < act["lif2"].peak < 0.05
    line = silence_warning(g, act, "these inputs", 100)
    assert line.startswith("the model never spikes in float on these inputs: population 'lif2' stays silent")
    assert "likely cause: threshold or gain scale" in line and "\n" not in line


def test_a_wrong_dt_is_named_as_the_likely_cause():
    g = _graph("braille_zero_2023.nir", 1e-6)        # trained at 1e-4: time constants 222 to 1000 steps
    line = calibration_warning(g, 100)
    assert line is not None and "population 'lif1.lif' stays silent" in line
    assert "likely cause: dt; at dt = 1e-06 s its time constants are 222.2 to 1000 steps" in line
    assert "pass the dt the model was trained at (--dt)" in line


def test_a_population_that_comes_close_is_not_blamed_on_scale():
    g = _graph("two_lif_neurons.nir", 1e-4)
    act = population_activity(g, calibration_spikes(1, 100))
    assert act["lif1"].silent and act["lif1"].peak > 0.5
    assert "comes close" in silence_warning(g, act, "x", 100)


def test_compile_warns_once_and_records_the_warning(tmp_path, capsys):
    out = tmp_path / "z.net"
    code, stdout, err = run_cli(["compile", DATA / "braille_zero_2023.nir", "--dt", "1e-6", "-o", out, "--json"],
                                capsys)
    assert code == 0 and out.exists(), err
    warnings = [ln for ln in err.splitlines() if ln.startswith("snncc: warning:")]
    assert len(warnings) == 1 and "likely cause: dt" in warnings[0], err
    assert json.loads(stdout)["warnings"] == [warnings[0][len("snncc: warning: "):]]
    code, stdout, err = run_cli(["compile", DATA / "braille_zero_2023.nir", "--dt", "1e-4", "-o", out, "--json"],
                                capsys)
    assert code == 0 and "snncc: warning:" not in err and json.loads(stdout)["warnings"] == []


def test_a_target_that_ran_the_float_model_spares_compile_the_run(monkeypatch):
    """Loihi's lowering runs the float model on the calibration inputs (its scale rule is measured there): its
    figures equal the IR's, and compile's warning reads them instead of running the float model again."""
    import dataclasses

    import snncc.ir.liveness as liveness
    from snncc.targets import get_target
    from snncc.targets.base import KnowsFloatActivity

    g = _graph("braille_zero_2023.nir", 1e-4)
    artefact = get_target("loihi").lower(g, {})
    assert isinstance(artefact, KnowsFloatActivity)
    known = artefact.float_calibration_activity(256)
    assert artefact.float_calibration_activity(100) is None          # figures of another length are not used
    ir = population_activity(g, calibration_spikes(12, 256))
    assert {k: (a.spikes, a.silent_neurons, a.saturated_neurons) for k, a in known.items()} == \
        {k: (a.spikes, a.silent_neurons, a.saturated_neurons) for k, a in ir.items()}
    monkeypatch.setattr(liveness, "population_activity", lambda *a: (_ for _ in ()).throw(AssertionError("ran")))
    assert calibration_warning(g, 256, known) is None
    silent = {**known, "lif2": dataclasses.replace(known["lif2"], spikes=0)}
    try:
        calibration_warning(g, 256, silent)                          # a silent population: the float model runs
    except AssertionError as ran:
        assert str(ran) == "ran"
    else:
        raise AssertionError("a silent population in the known figures must run the float model")
