"""The Xylo lowering end to end on small chains: the spec contract, the rules' guarantees, refusals."""

import json

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir import LIF, LSTM, Dense, Graph, Input, Output, Readout
from snncc.ir.simulate import simulate
from snncc.targets.kit.agreement import argmax_agreement
from xylo_models import lower_with

from xylo_models import chain, run_xylosim, spikes

QUICK = {"calibration_samples": 24, "time_steps": 80, "density": 0.15}
SPEC_KEYS = {"weights_in": np.int8, "weights_rec": np.int8, "weights_out": np.int8, "dash_mem": np.uint8,
             "dash_syn": np.uint8, "dash_syn_2": np.uint8, "dash_mem_out": np.uint8, "dash_syn_out": np.uint8,
             "threshold": np.int16, "threshold_out": np.int16, "bias": np.int16, "bias_out": np.int16}


def chip_counts(low, x):
    out = run_xylosim(low.spec, low.chip_input(x), record=True)
    return low.read_output(out.output_spikes, x.shape[1]).sum(axis=1), out


def float_counts(g, x, node="out"):
    return np.asarray(simulate(g, x, record="spikes").spikes[node]).sum(axis=1)


@pytest.fixture(scope="module")
def model():
    return chain(np.random.default_rng(5), n_in=6, n_hidden=12, n_out=3, beta=0.85, alpha_o=0.45, beta_o=0.7)


def test_spec_contract(model):
    low = lower_with(model, dict(QUICK, rule="single"))
    spec = low.spec
    for key, dtype in SPEC_KEYS.items():
        assert spec[key].dtype == dtype, key
    assert spec["weights_in"].shape == (6, 12, 2) and spec["weights_rec"].shape == (12, 12, 2)
    assert spec["weights_out"].shape == (12, 3) and spec["threshold_out"].shape == (3,)
    assert all(isinstance(spec[k], int) and 0 <= spec[k] <= 8 for k in
               ("weight_shift_in", "weight_shift_rec", "weight_shift_out"))
    assert spec["aliases"] == [[] for _ in range(12)] and spec["dt"] == model.dt
    assert set(SPEC_KEYS) | {"weight_shift_in", "weight_shift_rec", "weight_shift_out", "aliases", "dt"} == set(spec)
    rec = json.loads(json.dumps(low.record()))
    assert rec["rule"].startswith("single") and rec["populations"][0]["method"] == "single"
    assert rec["real_time"]["real_time"] in (True, False) and rec["real_time"]["cycles_worst"] > 0


def test_single_rule_fires_once_per_step_on_the_chip_and_follows_the_float_graph(model):
    low = lower_with(model, dict(QUICK, rule="single-identified"))
    assert np.all(low.spec["threshold"] >= 2 ** 14 + 1) and np.all(low.spec["dash_mem"] == 0)
    x = spikes(np.random.default_rng(11), 60, 80, 6, 0.15)
    counts, out = chip_counts(low, x)
    assert out.spikes.max() == 1                   # a 16-bit V cannot hold two thresholds
    assert out.spikes.sum() > 500                   # active
    agr = argmax_agreement(float_counts(model, x), counts)
    assert agr.decided > 30 and agr.share >= 0.75, agr.text()


def test_direct_rule_fires_several_spikes_per_step_and_says_so(model):
    low = lower_with(model, dict(QUICK, rule="direct"))
    x = spikes(np.random.default_rng(12), 20, 80, 6, 0.3)
    _, out = chip_counts(low, x)
    assert out.spikes.max() > 1
    assert low.twin.node("hidden").max_spikes == 31 and low.twin.node("hidden").fire_test == ">="
    assert any("31 spikes per step" in n for n in low.notes)


def test_auto_keeps_the_best_measured_candidate(model):
    low = lower_with(model, dict(QUICK, rule="auto"))
    scores = {k: v["share"] for k, v in low.candidates.items()}
    assert len(scores) >= 3 and "direct" in scores
    assert scores[low.rule] == max(scores.values())


def test_zero_reset_is_refused_unless_allowed():
    g = chain(np.random.default_rng(1), reset="zero")
    with pytest.raises(SnnccError) as err:
        lower_with(g, dict(QUICK, rule="direct"))
    assert "cannot reset to zero" in str(err.value) and err.value.field == "node 'hidden'.reset"
    low = lower_with(g, dict(QUICK, rule="direct", allow_reset_change=True))
    assert low.changes == ["hidden: reset zero -> subtract (Xylo subtracts the threshold)",
                           "out: reset zero -> subtract (Xylo subtracts the threshold)"]
    assert low.reference.node("hidden").reset == "subtract" and g.node("hidden").reset == "zero"


@pytest.mark.parametrize("mutate, match", [
    (lambda g: setattr(g.node("hidden"), "refractory", 2), "refractory: 2 steps"),
    (lambda g: setattr(g.node("input"), "signal", "analog"), "spike events"),
    (lambda g: setattr(g.node("hidden"), "max_spikes", 3), "standard spike rule"),
])
def test_what_xylo_cannot_express_is_one_line(mutate, match):
    g = chain(np.random.default_rng(2))
    mutate(g)
    with pytest.raises(SnnccError, match=match):
        lower_with(g, dict(QUICK, rule="direct"))


def test_lstm_and_a_readout_without_hidden_neurons_are_refused():
    g = Graph(1e-3)
    g.add("input", Input(4))
    g.add("lstm", LSTM(np.zeros((8, 4)), np.zeros((8, 2))))
    g.add("fc", Dense(np.zeros((2, 2))))
    g.add("readout", Readout(2, mode="last"))
    g.add("output", Output(2))
    for u, v in (("input", "lstm"), ("lstm", "fc"), ("fc", "readout"), ("readout", "output")):
        g.connect(u, v)
    with pytest.raises(SnnccError, match="LSTM cannot run on Xylo"):
        lower_with(g, QUICK)
    g = Graph(1e-3)
    g.add("input", Input(4))
    g.add("w", Dense(np.ones((2, 4))))
    g.add("out", LIF(2, 1e-2, 1e-2, 1.0, reset="subtract"))
    g.add("readout", Readout(2))
    g.add("output", Output(2))
    for u, v in (("input", "w"), ("w", "out"), ("out", "readout"), ("readout", "output")):
        g.connect(u, v)
    with pytest.raises(SnnccError, match="only through hidden neurons"):
        lower_with(g, QUICK)


def test_calibration_inputs_and_options_are_checked(model):
    with pytest.raises(SnnccError, match="calibration inputs must be"):
        lower_with(model, {"calibration": np.zeros((4, 10, 5))})
    with pytest.raises(SnnccError, match="rule must be one of"):
        lower_with(model, {"rule": "fine"})
    with pytest.raises(SnnccError, match="chip must be one of"):
        lower_with(model, {"chip": "loihi"})


def test_biases_ride_on_the_register_and_an_always_on_source_neuron():
    """Hidden current and voltage biases and an output current bias, with no input at all: the chip's spikes
    come from the biases alone and follow the IR's ramp (decays on the grid: the kernels are exact)."""
    rng = np.random.default_rng(8)
    g = chain(rng, n_in=4, n_hidden=6, n_out=2, alpha=0.75, beta=0.875, alpha_o=0.5, beta_o=0.75,
              bias=np.linspace(-0.02, 0.06, 6), rec_scale=0.05)
    g.node("w_in").bias = np.linspace(0.01, 0.05, 6)
    g.node("w_out").bias = np.array([0.2, 0.35])
    x = np.zeros((2, 80, 4), np.uint8)
    low = lower_with(g, dict(QUICK, rule="single"))
    n = low.spec["threshold"].size
    assert n == 7 and low.spec["bias"][6] == low.spec["threshold"][6]        # the source: last hidden neuron
    assert any("always-on source neuron: exact" in note for note in low.notes)
    counts, out = chip_counts(low, x)
    ref = simulate(g, x, record="spikes")
    assert out.spikes[:, :, 6].min() == 1                                  # it fires every step
    want_h = np.asarray(ref.spikes["hidden"])
    got_h = out.spikes[:, :80, :6]
    assert want_h.sum() > 10
    # the same spikes up to the rounding of small weights (G ~ 100 chip units per threshold): counts within one
    # spike per neuron, first spikes within one step
    assert np.abs(got_h.sum(axis=1) - want_h.sum(axis=1)).max() <= 1
    first = lambda s: np.where(s.any(axis=1), s.argmax(axis=1), -1)  # noqa: E731
    assert np.abs(first(got_h) - first(want_h)).max() <= 1
    assert np.abs(counts - float_counts(g, x)).max() <= 1 and counts.sum() > 5
