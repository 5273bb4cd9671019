"""The kernel's 32-bit update lanes, padded layout and grouped updates against the plain statement."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from snncc.errors import SnnccError
from snncc.targets.loihi.emulation.flat import LANES, Flat, update_groups
from snncc.targets.loihi.emulation.kernel import _decay32, _spike_list_at
from snncc.targets.loihi.emulation.emulator import PreparedNetwork, program, check_inputs, decay, reference_run
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from tests.loihi.helpers import even, random_network
from tests.loihi.emulation.test_kernel import _same


@njit
def _decay32_all(x, keep):
    out = np.zeros(x.size, np.int32)
    for i in range(x.size):
        out[i] = _decay32(x[i], keep[i])
    return out


def test_decay32_equals_the_chips_decay_over_the_whole_32_bit_range():
    rng = np.random.default_rng(5)
    edges = np.array([0, 1, -1, 4095, -4095, 4096, -4096, 2**23 - 1, -(2**23), 2**31 - 1, -(2**31 - 1),
                      2**31 - 4096, -(2**31 - 4096)], np.int64)
    x = np.concatenate([edges, rng.integers(-(2**31 - 1), 2**31, 20_000), rng.integers(-(2**24), 2**24, 20_000)])
    for keep_values in ([0, 1, 2, 4095, 4096], list(rng.integers(0, 4097, 8))):
        for k in keep_values:
            keep = np.full(x.size, k, np.int64)
            got = _decay32_all(x.astype(np.int32), keep.astype(np.int32))
            assert np.array_equal(got.astype(np.int64), decay(x, 4096 - keep)), k


def test_spike_list_at_reads_only_its_layers_bytes():
    rng = np.random.default_rng(8)
    fired = np.zeros(64 * 6, np.uint8)
    words = fired.view(np.uint64)
    spk = np.zeros(fired.size, np.int32)
    for at in (0, 8, 32, 64, 96):
        for m in (1, 31, 32, 33, 64, 65, 150):
            for p in (0.0, 0.05, 0.5, 1.0):
                fired[:] = rng.random(fired.size) < p
                fired[at + m:] = 1                       # the next layer's bytes must be ignored
                c = _spike_list_at(words, at, m, spk)
                assert spk[:c].tolist() == np.flatnonzero(fired[at:at + m]).tolist(), (at, m, p)


@pytest.mark.parametrize("seed, kwargs", [
    (20, {}), (24, {"big": True}), (25, {"split_exponents": True}), (26, {"profiles": True}),
    (27, {"profiles": True, "big": True, "per_synapse_delays": False}), (28, {"recurrent": False}),
])
def test_32_bit_lanes_are_used_and_exact(seed, kwargs):
    """The random networks run in 32-bit lanes (with and without the wraps) and match the statement."""
    net = random_network(seed, **kwargs)
    flat = Flat(program(net))
    assert flat.fits32[1:].all()
    x = (np.random.default_rng(seed).random((5, 40, 7)) < 0.3).astype(np.uint8)
    fast = PreparedNetwork(net).run(x, record="all", threads=2)
    _same(fast, reference_run(net, x, record="all"), "all")
    if kwargs.get("big"):
        assert fast.overflow["q_wrap"] > 0                       # the 32-bit wrap path counted


def _wide_v_network(vmax: int, bias: int, vmin: int | None = None) -> LoihiNetwork:
    rng = np.random.default_rng(3)
    hidden = LoihiLayer("hidden", "dense_rec", 37, weight=even(rng, (37, 9)), weight_rec=even(rng, (37, 37)),
                        wgt_exp=7, wgt_exp_rec=5, v_th_mant=2**17 - 1, i_decay=64, v_decay=1, ref_delay=2,
                        vmin=-vmax if vmin is None else vmin, vmax=vmax, bias=np.full(37, bias), bias_exp=7)
    out = LoihiLayer("out", "dense", 3, weight=even(rng, (3, 37)), wgt_exp=0, v_th_mant=3000, i_decay=100,
                     v_decay=200, vmin=-vmax if vmin is None else vmin, vmax=vmax)
    return LoihiNetwork([LoihiLayer("input", "input", 9), hidden, out], t_sample=60)


@pytest.mark.parametrize("vmax, bias, fits", [
    (2**23 - 1, 100, True),                  # the chip's default range
    (2**31 - 2**23 - 2**14, 100, True),      # widest v with |decay(v)| + |u| + |bias| still in int32
    (2**31 - 2**23 - 2**14, 2**8, False),    # one bias step more and it may not be
    (2**31 - 1, 0, False),                   # 32-bit state, 64-bit arithmetic
])
def test_32_bit_lanes_only_where_every_value_fits(vmax, bias, fits):
    net = _wide_v_network(vmax, bias)
    flat = Flat(program(net))
    assert bool(flat.fits32[1]) is fits
    x = (np.random.default_rng(4).random((3, 60, 9)) < 0.6).astype(np.uint8)
    fast = PreparedNetwork(net).run(x, record="all", threads=1)
    ref = reference_run(net, x, record="all")
    _same(fast, ref, "all")
    if vmax > 2**24:
        assert np.abs(ref.voltage[1]).max() > 2**24              # v really leaves the chip's default range
    assert ref.overflow["u_wrap"] > 0                          # and the 32-bit wrap path is exercised


def test_padding_lanes_stay_out_of_the_clip_count_when_v_zero_is_clipped():
    """vmin > 0: v = 0 is clipped, so the padding slots must not be updated (nor counted)."""
    net = _wide_v_network(2**23 - 1, 5, vmin=10)
    x = (np.random.default_rng(6).random((4, 60, 9)) < 0.4).astype(np.uint8)
    fast = PreparedNetwork(net).run(x, record="all", threads=1)
    _same(fast, reference_run(net, x, record="all"), "all")
    assert fast.overflow["v_clip"] > 0


def test_kernel_layout_pads_every_layer_to_whole_vectors():
    flat = Flat(program(random_network(20)))
    assert np.all(flat.kn % LANES == 0) and np.all(flat.kn >= flat.prog.n)
    assert np.array_equal(flat.koff, np.concatenate([[0], np.cumsum(flat.kn)[:-1]]))
    pad = np.ones(flat.kn.sum(), bool)
    for i, (lo, n) in enumerate(zip(flat.koff, flat.prog.n)):
        pad[lo:lo + n] = False
    assert np.all(flat.keep_u[pad] == 0) and np.all(flat.bias[pad] == 0) and np.all(flat.vth[pad] == 2**31 - 1)


def test_update_groups_join_only_like_layers_with_inert_padding():
    lay = np.zeros((5, 6), np.int64)
    lay[1:] = [2, -100, 100, 7, 1, 1]
    inert = np.ones(5, bool)
    assert update_groups(lay, inert).tolist() == [[1, 5]]
    lay[3, 0] = 3                                               # another refractory delay
    assert update_groups(lay, inert).tolist() == [[1, 3], [3, 4], [4, 5]]
    lay[3, 0] = 2
    inert[2] = False                                            # layer 2's padding is skipped
    assert update_groups(lay, inert).tolist() == [[1, 3], [3, 5]]


def _deep_network(ref_delays) -> LoihiNetwork:
    """Input 13 -> 40 (recurrent) -> 33 -> 6, each layer's refractory delay given."""
    rng = np.random.default_rng(11)
    sizes = [13, 40, 33, 6]
    layers = [LoihiLayer("input", "input", sizes[0])]
    for i in range(1, 4):
        lay = LoihiLayer(f"l{i}", "dense_rec" if i == 1 else "dense", sizes[i], weight=even(rng, (sizes[i], sizes[i - 1])),
                         wgt_exp=2, v_th_mant=int(rng.integers(40, 400)), i_decay=int(rng.integers(100, 4000)),
                         v_decay=int(rng.integers(100, 4000)), ref_delay=ref_delays[i - 1], delay=i % 2)
        if i == 1:
            lay.weight_rec = even(rng, (40, 40))
            lay.delay_rec = 1
            lay.wgt_exp_rec = 2
        layers.append(lay)
    return LoihiNetwork(layers, t_sample=50)


@pytest.mark.parametrize("ref_delays, groups", [((2, 2, 2), 1), ((1, 2, 2), 2), ((2, 3, 2), 3)])
@pytest.mark.parametrize("batch", [1, 7, 1500])
def test_grouped_updates_any_batch_size(ref_delays, groups, batch):
    net = _deep_network(ref_delays)
    prepared = PreparedNetwork(net)
    lay = np.zeros((4, 6), np.int64)
    lay[:, 0], lay[:, 1], lay[:, 2] = prepared.flat.prog.params[:, 3], -(2**23 - 1), 2**23 - 1
    lay[:, 3], lay[:, 4], lay[:, 5] = prepared.flat.shift, prepared.flat.in_range, prepared.flat.fits32
    assert len(update_groups(lay, np.ones(4, bool))) == groups
    x = (np.random.default_rng(batch).random((batch, 50, 13)) < 0.25).astype(np.uint8)
    record = "all" if batch < 100 else "outputs"
    fast = prepared.run(x, record=record)
    _same(fast, reference_run(net, x, record=record), record)
    assert fast.output_spikes.any()


@pytest.mark.parametrize("data, message", [
    (np.full((2, 5, 7), 2, np.uint8), "binary"),
    (np.zeros((0, 5, 7), np.uint8), "empty"),
    (np.ones((2, 5, 6), np.uint8), "channels"),
    (np.full((2, 5, 7), -1, np.int8), "binary"),
])
def test_check_inputs_fast_path_refuses_what_the_shared_rules_refuse(data, message):
    with pytest.raises(SnnccError, match=message):
        check_inputs(data, 7)


@pytest.mark.parametrize("dtype", [np.uint8, np.bool_, np.uint16, np.int64, np.float32])
def test_check_inputs_accepts_binary_data_of_any_numeric_type(dtype):
    x = (np.random.default_rng(1).random((3, 5, 7)) < 0.5).astype(dtype)
    got = check_inputs(x, 7)
    assert got.dtype == np.uint8 and np.array_equal(got, x.astype(np.uint8))
