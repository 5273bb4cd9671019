"""Xylo's time model stated in the IR: the spec's twin against xylosim step for step, and the shifts
that make a lowered chain exact in time."""

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir.simulate import simulate
from snncc.targets.xylo import feed
from snncc.targets.xylo.lowering.structure import populations
from snncc.targets.xylo.lowering.timing import solve_timing
from snncc.targets.xylo.lowering.twin import spec_graph

from xylo_models import chain, run_xylosim, spikes


def impulse_spec():
    """One input, one hidden neuron (two synapses), one output; power-of-two states keep every decay exact
    for the steps compared (dash 1 halves 2^k exactly)."""
    return dict(weights_in=np.array([[[64, 32]]], np.int8), weights_rec=np.array([[[-16, 0]]], np.int8),
                weights_out=np.array([[64]], np.int8), dash_syn=[1], dash_syn_2=[1], dash_mem=[1],
                dash_syn_out=[1], dash_mem_out=[1], threshold=[150], threshold_out=[64], bias=[0], bias_out=[0],
                weight_shift_in=2, weight_shift_rec=2, weight_shift_out=2)


def test_twin_equals_xylosim_step_for_step_on_an_exact_impulse():
    spec = impulse_spec()
    x = np.zeros((1, 6, 1), np.uint8)
    x[0, 0] = 1
    chip = run_xylosim(spec, x, record=True)
    twin = simulate(spec_graph(spec, 1e-3), x, record="all")
    # input delivered and integrated in the same step (i = a (i + w)): 256 -> 128, 128 -> 64, V = 192 >= 150
    assert chip.isyn[0, :2, 0].tolist() == [128, 32] and chip.vmem[0, 0, 0] == 42
    # the spike of step 0 comes back through the recurrent weight (-64) in step 1, reaches the output in step 1
    assert chip.spikes[0, 0, 0] == 1 and chip.output_spikes[0, :2, 0].tolist() == [0, 1]
    for twin_key, chip_key in (("syn0", "isyn"), ("syn1", "isyn2"), ("hidden", "vmem"), ("output", "vmem_out")):
        # exact while every decayed value is even (85 >> 1 rounds down on the chip from step 2 on)
        np.testing.assert_array_equal(twin.voltage[twin_key][0, :2, 0], getattr(chip, chip_key)[0, :2, 0])
    np.testing.assert_array_equal(twin.spikes["hidden"][0, :4, 0], chip.spikes[0, :4, 0])
    np.testing.assert_array_equal(twin.spikes["output"][0, :4, 0], chip.output_spikes[0, :4, 0])


def test_twin_follows_xylosim_on_random_specs():
    rng = np.random.default_rng(3)
    n, n_in, m = 16, 5, 3
    spec = dict(weights_in=rng.integers(-40, 90, (n_in, n, 2)).astype(np.int8),
                weights_rec=np.zeros((n, n, 2), np.int8),
                weights_out=rng.integers(-30, 90, (n, m)).astype(np.int8), dash_syn=rng.integers(1, 4, n),
                dash_syn_2=rng.integers(1, 5, n), dash_mem=rng.integers(0, 4, n), dash_syn_out=rng.integers(1, 3, m),
                dash_mem_out=rng.integers(1, 3, m), threshold=rng.integers(3000, 5000, n),
                threshold_out=rng.integers(2000, 3000, m), bias=rng.integers(-20, 20, n), bias_out=np.zeros(m, int),
                weight_shift_in=5, weight_shift_rec=5, weight_shift_out=5)
    x = spikes(rng, 4, 120, n_in, 0.2)
    chip = run_xylosim(spec, x, record=True)
    twin = simulate(spec_graph(spec, 1e-3), x, record="spikes")
    hidden = np.asarray(twin.spikes["hidden"])
    assert chip.spikes.max() >= 2 and chip.spikes.sum() > 100          # active, with multi-spikes
    assert np.mean(hidden == chip.spikes) > 0.95                           # integer rounding aside
    late = np.roll(hidden, 1, axis=1)                                         # one step off is far worse
    assert np.mean(late == chip.spikes) < np.mean(hidden == chip.spikes) - 0.02


def hand_spec(g, timing):
    """A float spec stating ``g`` in the chip's order (w = W / alpha, no rounding): its twin must equal ``g``
    with the chip's spike rule (hidden: up to 31 spikes per step on V >= theta; output: one, on V >= theta)."""
    h, o = g.node("hidden"), g.node("out")
    a, b = h.decays(g.dt)
    ao, bo = o.decays(g.dt)
    dash = lambda v: np.round(-np.log2(1 - np.asarray(v))).astype(int)  # noqa: E731
    n = h.n
    w_in = g.node("w_in").weight / a[:, None]
    return dict(weights_in=np.stack([w_in.T, np.zeros_like(w_in.T)], 2),
                weights_rec=np.stack([(g.node("w_rec").weight / a[:, None]).T, np.zeros((n, n))], 2),
                weights_out=(g.node("w_out").weight / ao[:, None]).T,
                dash_syn=dash(a), dash_syn_2=dash(a), dash_mem=dash(b), dash_syn_out=dash(ao), dash_mem_out=dash(bo),
                threshold=h.threshold, threshold_out=o.threshold, bias=np.zeros(n), bias_out=np.zeros(o.n))


@pytest.mark.parametrize("delays", [(0, 1, 0), (1, 1, 1), (2, 1, 0), (0, 1, 3)])
def test_shifts_make_the_chip_order_exact(delays):
    rng = np.random.default_rng(sum(delays))
    g = chain(rng, delays=delays)
    timing = solve_timing(g, populations(g))
    # chip delays 0 (input) and 1 (output): s_hidden - s_input = -d_in, s_out - s_hidden = 1 - d_out, min s = 0
    s_h = -delays[0]
    s_o = s_h + 1 - delays[2]
    low = min(0, s_h, s_o)
    assert (timing.input_pad, timing.output_lag) == (-low, s_o - low)
    twin = spec_graph(hand_spec(g, timing), g.dt)
    g.node("hidden").max_spikes, g.node("hidden").fire_test, g.node("out").fire_test = 31, ">=", ">="
    x = spikes(rng, 6, 100, 6, 0.2)
    ref = simulate(g, x, record="spikes")
    out = simulate(twin, feed.chip_window(x, timing.input_pad, timing.output_lag), record="spikes")
    assert np.asarray(ref.spikes["hidden"]).max() > 1                            # several spikes per step happen
    got = feed.read_window(np.asarray(out.spikes["output"]), timing.output_lag, 100)
    want = np.asarray(ref.spikes["out"])
    assert want.sum() > 20
    np.testing.assert_array_equal(got, want)
    if timing.output_lag:                     # reading one step early is not exact
        early = feed.read_window(np.asarray(out.spikes["output"]), timing.output_lag - 1, 100)
        assert not np.array_equal(early, want)


def test_recurrent_delay_other_than_one_is_refused():
    g = chain(np.random.default_rng(0), delays=(0, 3, 0))
    with pytest.raises(SnnccError, match="recurrent projection with IR delay 3"):
        solve_timing(g, populations(g))
