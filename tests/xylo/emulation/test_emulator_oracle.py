"""snncc's Xylo emulator against the vendor's simulator (xylosim 0.1.3, driven directly): spike for
spike and state for state on random active networks, at the chips' limits, and on the rule cases
that separate plausible readings of the arithmetic.

The random networks must exercise what makes the chip's arithmetic hard, or the comparison proves
little: every test that draws networks asserts, over its examples, that currents and membranes
saturated, that event counts hit the caps (input 15, hidden 31, output 1), that shifted weights
wrapped in int16, and that no network was silent.
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snncc.targets.xylo.chip import CHIPS, CORE
from snncc.targets.xylo.emulation import vectorized
from snncc.targets.xylo.emulation.emulator import STATE_NAMES, check_inputs, emulate, reference_run
from snncc.targets.xylo.spec import XyloSpec
from tests.xylo.networks import Knobs, chip_sized_knobs, random_inputs, random_spec
from tests.xylo.oracle import XyloSimOracle

FIELDS = ("output_spikes",) + STATE_NAMES


def assert_same(expected, got, label: str) -> None:
    for name in FIELDS:
        a, b = getattr(expected, name), getattr(got, name)
        assert a.shape == b.shape, f"{label}: {name} shape {b.shape} != {a.shape}"
        if not np.array_equal(a, b):
            where = tuple(int(i) for i in np.argwhere(a != b)[0])
            raise AssertionError(f"{label}: {name} differs first at (sample, step, neuron) {where}: "
                                 f"xylosim {a[where]}, snncc {b[where]}")


@st.composite
def knobs(draw, max_hidden: int = 40):
    n = draw(st.integers(1, max_hidden))
    return Knobs(
        seed=draw(st.integers(0, 2**32 - 1)),
        n_in=draw(st.integers(1, 16)), n_hidden=n, n_out=draw(st.integers(1, 8)),
        n_ien=draw(st.integers(1, n)), n_oen=draw(st.integers(1, n)),
        synapse_axis=draw(st.integers(0, 2)),
        shift_in=draw(st.integers(0, CORE.weight_shift_max)), shift_rec=draw(st.integers(0, CORE.weight_shift_max)),
        shift_out=draw(st.integers(0, CORE.weight_shift_max)),
        density=draw(st.floats(0.05, 1.0)), threshold_scale=draw(st.floats(0.05, 5.0)),
        bias_fraction=draw(st.floats(0.0, 1.0)), alias_fraction=draw(st.floats(0.0, 0.5)),
        negative_thresholds=draw(st.booleans()))


def check_coverage(stats: Counter, examples: int) -> None:
    """What the examples exercised (counts of examples in which each rule bit)."""
    assert stats["examples"] == examples
    assert stats["silent"] == 0, "a network emitted no hidden or no output event"
    for rule in ("current_saturations", "vmem_saturations", "input_clipped", "hidden_capped", "output_capped",
                 "wrapped_weight_deliveries", "threshold_wraps"):
        assert stats[rule] > 0, f"no example exercised {rule}: {dict(stats)}"


def run_and_compare(spec: XyloSpec, x: np.ndarray, stats: Counter, label: str) -> None:
    """xylosim, the kernel (1 and 2 threads) and the numpy reference agree; ``stats`` counts the rules hit."""
    expected = XyloSimOracle(spec).run(x, record=True)
    assert_same(expected, emulate(spec, x, record=True), f"{label} kernel")
    assert_same(expected, emulate(spec, x, record=True, threads=2), f"{label} kernel, 2 threads")
    if vectorized.plain(spec):
        assert_same(expected, vectorized.run(spec, check_inputs(x, spec.n_in), record=True), f"{label} vectorised")
        stats["vectorised"] += 1
    counted = reference_run(spec, x, record=True, count=True)
    assert_same(expected, counted, f"{label} numpy reference")
    stats["examples"] += 1
    stats["silent"] += int(expected.spikes.sum() == 0 or expected.output_spikes.sum() == 0)
    for rule, times in counted.events.items():
        stats[rule] += int(times > 0)


def test_random_networks_equal_xylosim_spike_for_spike_and_state_for_state():
    stats = Counter()

    @settings(max_examples=45, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(k=knobs(), batch=st.integers(1, 3), steps=st.integers(1, 40), density=st.floats(0.05, 0.6),
           max_count=st.sampled_from([1, 15, 40]))
    def check(k, batch, steps, density, max_count):
        spec = random_spec(k)
        x = random_inputs(k.seed ^ 0x5EED, batch, steps, spec.n_in, density, max_count)
        run_and_compare(spec, x, stats, f"{k}")

    check()
    check_coverage(stats, 45)
    assert stats["vectorised"] >= 5, dict(stats)


@pytest.mark.parametrize("key", sorted(CHIPS))
def test_networks_at_each_chips_limits_equal_xylosim(key):
    """All inputs, hidden and output neurons, expansion neurons, synapses and fan-out a chip allows."""
    chip = CHIPS[key]
    spec = random_spec(chip_sized_knobs(chip, seed=7))
    spec.check_chip(chip)
    assert (spec.n_hidden, spec.n_out, spec.n_ien, spec.n_oen) == (
        chip.max_hidden, chip.max_outputs, chip.max_input_expansion, chip.max_output_expansion)
    x = random_inputs(11, 2, 12, spec.n_in, 0.3, 20)
    expected = XyloSimOracle(spec).run(x, record=True)
    got = emulate(spec, x, record=True)
    assert_same(expected, got, key)
    if vectorized.plain(spec):
        assert_same(expected, vectorized.run(spec, check_inputs(x, spec.n_in), record=True), f"{key} vectorised")
    assert got.spikes.sum() > 0 and got.output_spikes.sum() > 0 and (x > CORE.max_input_spikes).any()
    capped = (got.spikes == CORE.max_hidden_spikes) & (got.vmem >= spec.threshold)   # 31 events, V still >= th
    assert capped.any()


def test_dense_kernel_path_and_no_alias_fast_path_equal_xylosim():
    """Dense rows, no aliases and positive thresholds: the kernel's all-at-once event path."""
    stats = Counter()
    for seed in range(6):
        k = Knobs(seed=seed, n_in=12, n_hidden=40, n_out=7, n_ien=40, n_oen=40, synapse_axis=seed % 3,
                  shift_in=seed + 2, shift_rec=seed + 1, shift_out=seed + 2, density=1.0, threshold_scale=0.5,
                  bias_fraction=0.2, alias_fraction=0.0, negative_thresholds=False)
        spec = random_spec(k)
        assert not any(spec.aliases) and spec.threshold.min() > 0
        run_and_compare(spec, random_inputs(seed, 2, 60, 12, 0.2, 20), stats, f"dense {seed}")
    assert stats["silent"] == 0 and stats["hidden_capped"] and stats["current_saturations"]
    assert stats["vectorised"] == 6


def one_neuron(**overrides) -> XyloSpec:
    """One input, one hidden neuron, one output: the rule cases below set what they need."""
    fields = dict(weights_in=[[0]], weights_rec=[[0]], weights_out=[[0]], dash_mem=[15], dash_syn=[15],
                  dash_syn_2=[15], dash_mem_out=[15], dash_syn_out=[15], threshold=[32767], threshold_out=[32767],
                  bias=[0], bias_out=[0], weight_shift_in=0, weight_shift_rec=0, weight_shift_out=0,
                  aliases=[[]], dt=1e-3)
    fields.update(overrides)
    return XyloSpec(**fields)


def test_summed_currents_are_not_saturated_before_they_reach_v():
    """V += sat(sat(-decay(V) + Isyn + Isyn2) + bias): the two currents are summed exactly, then
    saturated once, and only then added to V. Reached through inputs: step 0 gives Isyn 32511 and V
    32511; step 1 saturates Isyn at 32767 and Isyn2 at -32768 (two events of -128 << 8), which decay
    (dash 15) to 32766 and -32767, so V = 32511 - 1 + (32766 - 32767) = 32509. Adding the currents
    to V one at a time, saturating each sum, would give sat(sat(32511 + 32766) - 32767) - 1 = -1."""
    spec = one_neuron(weights_in=[[[127, 0]], [[0, -128]]], weight_shift_in=8)
    x = np.zeros((1, 3, 2), np.uint8)
    x[0, 0, 0] = 1
    x[0, 1] = (1, 2)
    expected = XyloSimOracle(spec).run(x, record=True)
    got = reference_run(spec, x, record=True)
    assert_same(expected, got, "saturation order")
    assert got.vmem[0, 0, 0] == 32511
    assert (got.isyn[0, 1, 0], got.isyn2[0, 1, 0], got.vmem[0, 1, 0]) == (32766, -32767, 32509)
    sat = lambda z: min(max(z, -32768), 32767)   # noqa: E731
    assert sat(sat(32511 + 32766) - 32767) - 1 == -1


def test_the_spec_pages_saturation_example_by_the_reference_rules():
    """shared/spec/xylo.md: Isyn 32763, Isyn2 -32767 (after their decay) and V 32764 give V 32759."""
    from snncc.targets.xylo.emulation.literal import _Counter, _evolve_states

    before_decay = np.array([[[32764, -32768]]])    # dash 15: 32764 - 1 = 32763, -32768 + 1 = -32767
    isyn, v = _evolve_states(before_decay, np.array([[32764]]), np.array([[15, 15]]), np.array([15]),
                             np.array([0]), _Counter(False))
    assert isyn[0, 0].tolist() == [32763, -32767]
    assert v[0, 0] == 32759                        # 32764 - 1 + (32763 - 32767)


@pytest.mark.parametrize("shift,weight,effective", [(8, 127, 32512), (9, 127, -512), (15, 127, -32768),
                                                     (9, -128, 0), (10, 3, 3072), (15, 1, -32768)])
def test_shifted_weights_wrap_in_int16_as_in_xylosim(shift, weight, effective):
    spec = one_neuron(weights_in=[[weight]], weight_shift_in=shift, dash_syn=[15])
    x = np.zeros((1, 2, 1), np.uint8)
    x[0, 0, 0] = 1
    expected = XyloSimOracle(spec).run(x, record=True)
    got = emulate(spec, x, record=True)
    assert_same(expected, got, f"{weight} << {shift}")
    d = 1 if effective > 0 else (-1 if effective < 0 else 0)   # dash 15: decay by sign(I) (>> 15 is 0 or -1)
    assert got.isyn[0, 0, 0] == effective - d


def test_leak_of_the_most_negative_v_with_dash_zero_wraps():
    """dv = -(V >> 0) with V = -32768 is +32768, narrowed to int16: -32768, so V stays at -32768
    (without the wrap it would leak to 0 + the currents). The two synapses together drive V there."""
    spec = one_neuron(weights_in=[[[-128, -128]]], weight_shift_in=8, dash_mem=[0], threshold=[100])
    x = np.full((1, 5, 1), 2, np.uint8)
    expected = XyloSimOracle(spec).run(x, record=True)
    got = reference_run(spec, x, record=True, count=True)
    assert_same(expected, got, "decay wrap")
    assert got.events["decay_wraps"] > 0 and got.vmem.min() == -32768


def test_alias_events_count_against_the_targets_own_cap_and_reach_earlier_targets_as_counts_only():
    """Neuron 1 aliases to neuron 0 (evolved earlier: its count rises, its V does not change) and to
    itself; neuron 0 aliases to neuron 2 (evolved later: it starts from those events, so it emits
    fewer and subtracts less). Checked against xylosim, states included."""
    w_in = [[[60, 0], [60, 0], [60, 0]]]
    spec = XyloSpec(weights_in=w_in, weights_rec=np.zeros((3, 3, 2), int), weights_out=[[5], [5], [5]],
                    dash_mem=[4, 4, 4], dash_syn=[2, 2, 2], dash_syn_2=[2, 2, 2], dash_mem_out=[4], dash_syn_out=[2],
                    threshold=[20, 20, 20], threshold_out=[50], bias=[0, 0, 0], bias_out=[0],
                    weight_shift_in=4, weight_shift_rec=0, weight_shift_out=0, aliases=[[2], [0, 1], []], dt=1e-3)
    x = np.zeros((1, 8, 1), np.uint8)
    x[0, :3, 0] = 15
    expected = XyloSimOracle(spec).run(x, record=True)
    got = emulate(spec, x, record=True)
    assert_same(expected, got, "aliases")
    assert got.spikes.max() == CORE.max_hidden_spikes
    assert not np.array_equal(got.vmem[0, :, 0], got.vmem[0, :, 2])   # same input, different V: aliases count


def test_input_counts_above_15_are_clipped_like_the_chip():
    spec = one_neuron(weights_in=[[1]], dash_syn=[15])
    x = np.array([[[15], [16], [200]]], np.uint8)
    expected = XyloSimOracle(spec).run(x, record=True)
    got = emulate(spec, x.astype(np.int64) * 1, record=True)
    assert_same(expected, got, "clipping")
    assert np.array_equal(emulate(spec, np.array([[[15], [15], [15]]])).output_spikes, got.output_spikes)
