"""Sigma-delta relays and the readout copied to the output neurons (the ``relayed`` rule), against XyloSim."""

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir.simulate import simulate
from snncc.targets.kit.agreement import argmax_agreement
from snncc.targets.xylo import feed
from snncc.targets.xylo.lowering import sigma_delta as relays
from snncc.targets.xylo.lowering.integers import COPY_WEIGHT
from xylo_models import lower_with

from xylo_models import chain, run_xylosim, spikes

QUICK = {"calibration_samples": 32, "time_steps": 80, "density": 0.15}


def _relay_spec(n, w8, shift, theta, dash):
    """n relays, relay j fed by input channel j, nothing else (output neurons idle)."""
    spec = {"weights_in": np.zeros((n, n, 2), np.int8), "weights_rec": np.zeros((n, n, 2), np.int8),
            "weights_out": np.zeros((n, 1), np.int8), "dash_mem": np.full(n, relays.RELAY_DASH_MEM, np.uint8),
            "dash_syn": np.full(n, dash, np.uint8), "dash_syn_2": np.full(n, dash, np.uint8),
            "dash_mem_out": np.zeros(1, np.uint8), "dash_syn_out": np.ones(1, np.uint8),
            "threshold": np.full(n, theta, np.int16), "threshold_out": np.full(1, 100, np.int16),
            "bias": np.zeros(n, np.int16), "bias_out": np.zeros(1, np.int16), "weight_shift_in": shift,
            "weight_shift_rec": 0, "weight_shift_out": 0}
    for j in range(n):
        spec["weights_in"][j, j, 0] = w8
    return spec


def _xylosim_equals_emulate(low, x):
    """XyloSim runs the lowered spec on ``x`` (fed the lowering's timing) with the output and hidden events and the
    membranes of snncc's emulator; returns XyloSim's run."""
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    chip_x = low.chip_input(x)
    vendor = run_xylosim(low.spec, chip_x, record=True)
    mine = emulate(XyloSpec(**low.spec), chip_x, record=True)
    assert np.array_equal(vendor.output_spikes, mine.output_spikes)
    assert np.array_equal(vendor.spikes, mine.spikes) and np.array_equal(vendor.vmem, mine.vmem)
    return vendor


@pytest.mark.parametrize("shift,dash", [(0, 3), (3, 2), (8, 2)])
def test_relay_events_are_the_chips(shift, dash):
    """``relay_events`` (what the identification sees) equals XyloSim's hidden events for the same registers,
    including several events per step and the remainder carried from step to step."""
    r = relays.Relay("x", 5, dash)
    w8, theta = r.registers(shift)
    assert 1 <= w8 <= 127 and theta >= 1
    z = spikes(np.random.default_rng(shift), 4, 150, 5, 0.3)
    mine = relays.relay_events(z, dash, w8, shift, theta)
    chip = run_xylosim(_relay_spec(5, w8, shift, theta, dash), z, record=True).spikes
    assert np.array_equal(mine, chip.astype(np.int64))
    assert mine.max() >= 2 and mine.sum() > 200           # multi-event steps, active
    # sigma-delta: the events track the filtered train (the gain), error bounded by one event
    a = 1 - 2.0 ** -dash
    f = np.zeros(z.shape[:1] + z.shape[2:])
    total = np.zeros_like(f)
    for t in range(z.shape[1]):
        f = a * (f + z[:, t])
        total += f
    want = total * r.gain(shift)
    assert np.all(np.abs(mine.sum(axis=1) - want) <= 0.03 * want + 2)


@pytest.mark.parametrize("dash", [1, 2, 3, 4, 6])          # 4, 6: a slower pair's second relay set (--relays both)
def test_relays_never_reach_the_cap_so_never_wind_up(dash):
    """A channel with an event on every step (the densest 0/1 train): the relay stays below 31 events a step, so
    no excess piles up in its membrane, and it falls silent within a few steps of its input stopping."""
    for shift in range(0, 9):
        r = relays.Relay("x", 1, dash)
        w8, theta = r.registers(shift)
        assert (w8 << shift) * (1 << dash) < 32767           # the current stays in range
        z = np.zeros((1, 200 + 14 * (1 << dash), 1), np.int64)
        z[0, :200] = 1
        ev = relays.relay_events(z, dash, w8, shift, theta)
        assert ev.max() <= 30 and ev[0, 150:200].min() >= 25   # near the bound, never the cap
        assert not ev[0, 200 + 12 * (1 << dash):].any()       # silent once the current has decayed


def test_readout_copy_is_exact():
    """A hidden readout copied to the output neurons one step later, exactly, whatever its spike train:
    bursts of every length, isolated spikes, silence (XyloSim)."""
    rng = np.random.default_rng(3)
    n_in, m = 4, 4
    # readout neurons 0..m-1 fire exactly when their input channel has a spike (memoryless, one spike per step)
    n = 2 * m
    spec = {"weights_in": np.zeros((n_in, n, 2), np.int8), "weights_rec": np.zeros((n, n, 2), np.int8),
            "dash_mem": np.zeros(n, np.uint8), "dash_syn": np.ones(n, np.uint8), "dash_syn_2": np.ones(n, np.uint8),
            "threshold": np.full(n, 32, np.int16), "bias": np.zeros(n, np.int16), "weight_shift_in": 0,
            "weight_shift_rec": 0}
    for j in range(m):
        spec["weights_in"][j, j, 0] = 64                 # i = 32 after the decay: V = 32, one event
        spec["weights_rec"][j, j, 0] = -32               # the own spike cancels the current's tail (32 - 32)
    from snncc.targets.xylo.lowering.integers import _copy_readout
    from snncc.targets.xylo.lowering.chip_form import HiddenFloat

    readout = HiddenFloat("r", "single", np.ones(m), np.ones((m, 2), np.int64), np.zeros(m, np.int64), {}, np.zeros(m))
    spec.update(_copy_readout(spec, readout, {"r": 0, "readout copy": m}, spec["weight_shift_rec"], n))
    x = np.zeros((3, 120, n_in), np.uint8)
    x[0] = rng.random((120, n_in)) < 0.5
    x[1, 10:60] = 1                                      # a 50-step burst
    x[1, 70:120:2] = 1
    res = run_xylosim(spec, x, record=True)
    hidden = res.spikes[:, :, :m]
    assert hidden.sum() > 100 and hidden.max() == 1
    assert np.array_equal(res.output_spikes[:, 1:], hidden[:, :-1])
    assert not res.output_spikes[:, 0].any()
    assert res.spikes[:, :, m:].max() == 1 and np.array_equal(res.spikes[:, 1:, m:], hidden[:, :-1])
    assert COPY_WEIGHT & (COPY_WEIGHT - 1) == 0          # a power of two: its halves are exact


@pytest.fixture(scope="module")
def model():
    return chain(np.random.default_rng(5), n_in=6, n_hidden=12, n_out=3, beta=0.85, alpha_o=0.45, beta_o=0.7)


def test_relayed_rule_runs_unchanged_in_xylosim_and_follows_the_float_graph(model):
    low = lower_with(model, dict(QUICK, rule="relayed"))
    rec = low.record()
    kinds = [p["role"] for p in rec["populations"]]
    assert kinds.count("relay") == 2 and low.rule.startswith("relayed")
    relay = [p for p in rec["populations"] if p["role"] == "relay"]
    assert [p["neurons"][1] - p["neurons"][0] for p in relay] == [6, 12]      # one per input channel, per neuron
    x = spikes(np.random.default_rng(11), 60, 80, 6, 0.15)
    vendor = _xylosim_equals_emulate(low, x)
    r0, r1 = relay[1]["neurons"]
    assert vendor.spikes[:, :, r0:r1].max() >= 2          # relays emit several events a step
    counts = low.read_output(vendor.output_spikes, x.shape[1]).sum(axis=1)
    agr = argmax_agreement(np.asarray(simulate(model, x, record="spikes").spikes["out"]).sum(axis=1), counts)
    assert agr.decided > 30 and agr.share >= 0.75, agr.text()


def test_auto_measures_relayed_candidates_with_the_readout_on_both_sides(model):
    low = lower_with(model, QUICK)
    names = list(low.candidates)
    assert any(n.startswith("relayed") and "readout on hidden" not in n for n in names)
    assert any("readout on hidden neurons" in n for n in names)


def test_readout_on_hidden_neurons_reads_one_step_later_and_is_exact_in_xylosim(model):
    """The candidate with the readout on hidden neurons: output neurons copy it, the output is read one chip step
    later, and the counts equal the readout population's on the chip."""
    from snncc.targets.xylo.chip import get_chip
    from snncc.targets.xylo.lowering.calibration import calibrate, sources as population_sources
    from snncc.targets.xylo.lowering.candidates import build_candidate, candidate_rules
    from snncc.targets.xylo.lowering.structure import populations
    from snncc.targets.xylo.lowering.timing import solve_timing

    pops = populations(model)
    timing = solve_timing(model, pops, readout_extra=1)
    sources = population_sources(model, pops, timing)
    x = spikes(np.random.default_rng(2), 32, 80, 6, 0.15)
    calibrate(model, sources, x)
    cand = next(c for c in candidate_rules(sources, "relayed", get_chip(None)) if c.readout == "hidden")
    spec, records = build_candidate(sources, 6, cand.method, cand.pairs, True, get_chip(None), timing, True, "hidden")
    assert [r.role for r in records][-1] == "output" and records[-1].method == "copy"
    readout = next(r for r in records if r.role == "readout")
    res = run_xylosim({**spec, "dt": 1e-3}, feed.chip_window(x, timing.input_pad, timing.output_lag), record=True)
    hid = res.spikes[:, :, readout.neurons[0]:readout.neurons[1]]
    assert hid.sum() > 50 and np.array_equal(res.output_spikes[:, 1:], hid[:, :-1])


def test_relayed_rule_is_refused_in_one_line_where_it_cannot_fit(model):
    with pytest.raises(SnnccError, match="two synaptic currents"):
        lower_with(model, dict(QUICK, rule="relayed", chip="syns63300"))
    big = chain(np.random.default_rng(1), n_in=16, n_hidden=60, n_out=3)
    with pytest.raises(SnnccError, match="relayed rule places .* hidden neurons; Xylo Audio 3") as err:
        lower_with(big, dict(QUICK, rule="relayed", chip="syns65302", density=0.1))
    assert "\n" not in str(err.value)


def test_an_unrounded_lowering_changes_only_the_weights(model):
    """rounding="none" (bench/studies/xylo_loss_sources.py measures what rounding costs with it): the same rule, dashes,
    thresholds, biases, shifts and relays as the written spec; every weight the float chip units it was rounded from
    (error feedback moves some by a few steps); refused without a float emulator."""
    from snncc.targets.xylo.lowering.twin import spec_graph

    def twin(spec, chip_x):
        return np.asarray(simulate(spec_graph(spec, model.dt), chip_x, record="spikes").spikes["output"])

    opts = dict(QUICK, rule="relayed", replicas=2)       # replicas: one candidate, so both choose the same
    written = lower_with(model, opts)
    unrounded = lower_with(model, dict(opts, rounding="none", emulator=twin))
    assert unrounded.rule == written.rule and "not estimated" in unrounded.real_time["note"]
    weights = ("weights_in", "weights_rec", "weights_out")
    for key, value in written.spec.items():
        if key in weights:
            got = unrounded.spec[key]
            assert got.dtype == np.float64 and value.dtype == np.int8
            used = (value != 0) | (got != 0)
            diff = np.abs(got[used] - value[used])
            assert np.any(got[used] != np.round(got[used]))                       # not integers
            assert diff.mean() < 3 and np.corrcoef(got[used], value[used])[0, 1] > 0.99, key
        elif isinstance(value, np.ndarray):
            assert np.array_equal(unrounded.spec[key], value), key
        else:
            assert unrounded.spec[key] == value, key
    for rec in (r for r in written.populations if r.role == "relay"):        # relays keep their integer registers
        a, b = rec.neurons
        assert np.array_equal(unrounded.spec["weights_in"][:, a:b], written.spec["weights_in"][:, a:b])
    x = spikes(np.random.default_rng(3), 4, 40, 6, 0.15)
    assert simulate(unrounded.twin, unrounded.chip_input(x), record="spikes").spikes["output"].shape[0] == 4
    with pytest.raises(SnnccError, match="needs an emulator"):
        lower_with(model, dict(opts, rounding="none"))
    with pytest.raises(SnnccError, match="rounding must be"):
        lower_with(model, dict(opts, rounding="fast"))


def test_relays_at_both_dashes_run_unchanged_in_xylosim(model):
    """``relays="both"``: every relayed source gets a second relay set at the slower synapse dash (named apart),
    in each copy of a replicated network; the spec dict still runs unchanged in XyloSim, state for state, and follows
    the float graph."""
    one = lower_with(model, dict(QUICK, rule="relayed"))
    low = lower_with(model, dict(QUICK, rule="relayed", relays="both", replicas=2))
    assert low.rule.startswith("relayed") and "relays at both dashes" in low.rule
    relay = [p for p in low.populations if p.role == "relay"]
    assert [p.name for p in relay] == ["relay of input#0", "relay of input#0 (dash 3)", "relay of hidden#0",
                                       "relay of hidden#0 (dash 3)", "relay of input#1", "relay of input#1 (dash 3)",
                                       "relay of hidden#1", "relay of hidden#1 (dash 3)"]
    assert [p.dashes["dash_syn"] for p in relay] == [[2], [3]] * 4
    n_one = one.spec["threshold"].size
    assert low.spec["threshold"].size == 2 * (n_one + 6 + 12)          # a second relay per channel, per copy
    x = spikes(np.random.default_rng(11), 60, 80, 6, 0.15)
    vendor = _xylosim_equals_emulate(low, x)
    for p in relay:                                                        # every relay set is active
        assert vendor.spikes[:, :, p.neurons[0]:p.neurons[1]].max() >= 2, p.name
    counts = low.read_output(vendor.output_spikes, x.shape[1]).sum(axis=1)
    agr = argmax_agreement(np.asarray(simulate(model, x, record="spikes").spikes["out"]).sum(axis=1), counts)
    assert agr.decided > 30 and agr.share >= 0.75, agr.text()


def test_relays_at_both_dashes_default_to_more_calibration_and_bad_values_are_refused(model):
    from snncc.targets.xylo.lowering.calibration import calibration_inputs
    from snncc.targets.xylo.options import (BOTH_CALIBRATION_SAMPLES, DEFAULT_CALIBRATION_SAMPLES, NO_KNOBS,
                                            XyloOptions)

    assert calibration_inputs(XyloOptions(relays="both"), NO_KNOBS, 2, 3).shape == (BOTH_CALIBRATION_SAMPLES, 3, 2)
    assert calibration_inputs(XyloOptions(), NO_KNOBS, 2, 3).shape[0] == DEFAULT_CALIBRATION_SAMPLES
    assert calibration_inputs(XyloOptions(relays="both", calibration_samples=8), NO_KNOBS, 2, 3).shape[0] == 8
    with pytest.raises(SnnccError, match="relays must be one of fast, both") as err:
        lower_with(model, dict(QUICK, relays="slow"))
    assert err.value.field == "--relays"


def test_relays_both_from_the_command_line(tmp_path, capsys, model):
    """``--relays both`` through ``snncc compile``: the manifest names the rule and the calibration it used; a bad
    value is one line, exit 2, nothing written."""
    import json

    from snncc.ir.serialize import save_graph
    from snncc_test_helpers import run_cli

    path = tmp_path / "chain.snnir"
    save_graph(model, path)
    out = tmp_path / "both.xylo"
    quick = ["--rule", "relayed", "--calibration-samples", "16", "--time-steps", "40"]
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--relays", "both", *quick, "-o", out], capsys)
    assert code == 0, err
    q = json.loads((out / "manifest.json").read_text())["quantization"]
    assert "relays at both dashes" in q["rule"] and q["calibration"]["inputs"].startswith("16 seeded")
    assert sum(p["role"] == "relay" for p in q["populations"]) == 4
    bad = tmp_path / "bad.xylo"
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--relays", "slow", *quick, "-o", bad], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--relays" in err and not bad.exists(), err
