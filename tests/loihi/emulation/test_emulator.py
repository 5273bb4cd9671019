"""The emulator against an independent step-by-step integer model of the chip (spec loihi.md §3)."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.targets.loihi.emulation.emulator import emulate, reference_run, wrap
from tests.loihi.helpers import chip_model, random_network


def _inputs(seed, batch=2, steps=40, width=7, p=0.3):
    return (np.random.default_rng(seed + 100).random((batch, steps, width)) < p).astype(np.uint8)


@pytest.mark.parametrize("seed, kwargs", [
    (0, {}), (1, {"recurrent": False}), (2, {"per_synapse_delays": False}), (3, {"bias": False}),
    (4, {}), (5, {"big": True}), (6, {"big": True, "per_synapse_delays": False}), (7, {"split_exponents": True}),
    (8, {"split_exponents": True, "recurrent": False}), (9, {"profiles": True}),
    (10, {"profiles": True, "big": True}),
])
def test_emulator_matches_independent_model_state_for_state(seed, kwargs):
    net = random_network(seed, **kwargs)
    x = _inputs(seed)
    fast = emulate(net, x, record="all")
    slow = reference_run(net, x, record="all")
    total = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    for b in range(x.shape[0]):
        s, u, v, counts = chip_model(net, x[b])
        for k in total:
            total[k] += counts[k]
        for i in range(1, len(net.layers)):
            assert np.array_equal(fast.spikes[i][b], s[i]), f"spikes layer {i}"
            assert np.array_equal(fast.current[i][b], u[i]), f"u layer {i}"
            assert np.array_equal(fast.voltage[i][b], v[i]), f"v layer {i}"
            assert np.array_equal(slow.spikes[i][b], s[i]) and np.array_equal(slow.voltage[i][b], v[i])
    assert fast.overflow == total == slow.overflow
    if kwargs.get("big"):
        assert total["q_wrap"] > 0 and total["u_wrap"] > 0, total   # the overflow cases are exercised
    assert np.array_equal(fast.output_spikes, fast.spikes[len(net.layers) - 1])
    assert np.array_equal(fast.counts, fast.output_spikes.sum(axis=1))


def test_stream_mode_is_one_continuous_run_with_gaps():
    net = random_network(7)
    x = _inputs(7, batch=3, steps=20)
    gap = 5
    res = emulate(net, x, mode="stream", gap=gap, record="all")
    stream = np.concatenate([np.concatenate([x[b], np.zeros((gap, 7), np.uint8)]) for b in range(3)])
    s, u, v, _ = chip_model(net, stream)
    for b in range(3):
        window = slice(b * 25, b * 25 + 20)
        assert np.array_equal(res.spikes[2][b], s[2][window])
        assert np.array_equal(res.voltage[1][b], v[1][window])
    batch = emulate(net, x)
    assert np.array_equal(batch.output_spikes[0], res.output_spikes[0])  # first sample starts from zero either way


def test_prediction_ties_go_to_lowest_index():
    net = random_network(8)
    res = emulate(net, np.zeros((2, 10, 7), np.uint8))
    assert np.all(res.counts == 0) and np.all(res.prediction == 0)


def test_wrap_is_twos_complement():
    vals = np.array([2**21 - 1, 2**21, -(2**21), -(2**21) - 1, 3 * 2**22 + 5], np.int64)
    assert wrap(vals, 21).tolist() == [2**21 - 1, -(2**21), -(2**21), 2**21 - 1, 5]


@pytest.mark.parametrize("bad, needle", [
    (np.zeros((4, 6)), "channels"),
    (np.full((4, 7), 0.5), "binary"),
    (np.full((4, 7), np.nan), "NaN"),
    (np.zeros((2, 2, 4, 7)), "shape"),
])
def test_bad_inputs_raise_one_clear_error(bad, needle):
    with pytest.raises(SnnccError, match=needle):
        emulate(random_network(0), bad)


def test_wide_mode_removes_overflow():
    net = random_network(5, big=True)
    x = _inputs(5)
    assert emulate(net, x).overflow["q_wrap"] > 0
    assert emulate(net, x, wide=True).overflow == {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
