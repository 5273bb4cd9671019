"""The kernel's fast paths (threads, narrow weight/accumulator/state types) against the plain statement."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.targets.loihi.emulation.flat import Flat, _common_shift, narrowest_int, q_u_in_range
from snncc.targets.loihi.emulation.kernel import _spike_list
from snncc.targets.loihi.emulation.emulator import PreparedNetwork, program, reference_run
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from tests.loihi.helpers import random_network


def _inputs(seed, batch, steps=40, width=7, p=0.3):
    return (np.random.default_rng(seed + 200).random((batch, steps, width)) < p).astype(np.uint8)


def _same(a, b, record):
    assert np.array_equal(a.output_spikes, b.output_spikes)
    assert np.array_equal(a.counts, b.counts) and np.array_equal(a.prediction, b.prediction)
    assert a.overflow == b.overflow
    if record == "all":
        for name in ("spikes", "voltage", "current"):
            mine, theirs = getattr(a, name), getattr(b, name)
            assert mine.keys() == theirs.keys()
            for i in mine:
                assert np.array_equal(mine[i], theirs[i]), f"{name} layer {i}"


@pytest.mark.parametrize("seed, kwargs", [
    (20, {}), (21, {"recurrent": False}), (22, {"per_synapse_delays": False}), (23, {"bias": False}),
    (24, {"big": True}), (25, {"split_exponents": True}), (26, {"profiles": True}),
    (27, {"profiles": True, "big": True, "per_synapse_delays": False}),
])
def test_threaded_batch_equals_serial_and_the_plain_statement(seed, kwargs):
    net = random_network(seed, **kwargs)
    x = _inputs(seed, batch=7)
    prepared = PreparedNetwork(net)
    for record in ("outputs", "all"):
        serial = prepared.run(x, record=record, threads=1)
        threaded = prepared.run(x, record=record, threads=3)      # 7 samples over 3 threads: uneven chunks
        _same(threaded, serial, record)
        _same(serial, reference_run(net, x, record=record), record)
    if kwargs.get("big"):                                          # the wrap paths are exercised
        assert serial.overflow["q_wrap"] > 0
    if kwargs == {"big": True}:
        assert serial.overflow["u_wrap"] > 0
    one_by_one = [prepared.run(x[b], threads=1).output_spikes[0] for b in range(len(x))]
    assert np.array_equal(np.stack(one_by_one), serial.output_spikes)   # batch 1 = a row of the batch


def test_wide_run_threaded_equals_serial():
    net = random_network(24, big=True)
    x = _inputs(24, batch=5)
    prepared = PreparedNetwork(net)
    a, b = prepared.run(x, wide=True, threads=1), prepared.run(x, wide=True, threads=2)
    assert a.overflow == b.overflow == {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    assert np.array_equal(a.output_spikes, b.output_spikes)


def _all_on_network(n_in: int, first: int, rest: int, i_decay: int = 4096) -> LoihiNetwork:
    """Input 0 reaches every hidden neuron with weight ``first``, the others with ``rest``."""
    w = np.full((3, n_in), rest, np.int16)
    w[:, 0] = first
    hidden = LoihiLayer("hidden", "dense", 3, weight=w, wgt_exp=0,
                        v_th_mant=2**17 - 1, i_decay=i_decay, v_decay=4096, vmin=-(2**23 - 1), vmax=2**23 - 1)
    out = LoihiLayer("out", "dense", 2, weight=np.full((2, 3), 2, np.int16), v_th_mant=1)
    return LoihiNetwork([LoihiLayer("input", "input", n_in), hidden, out], t_sample=6)


@pytest.mark.parametrize("n_in, first, rest, acc", [
    (258, 254, 254, np.int16),    # w_chip = 254 * 64 = 127 << 7; 258 * 127 = 32766 still fits int16
    (259, 254, 254, np.int32),    # 32893 does not
    (256, 254, -256, np.int16),   # 127 + 255 * 128 = 32767; stored weights 127 and -128 (int8)
])
def test_accumulator_type_at_its_limit_is_exact(n_in, first, rest, acc):
    net = _all_on_network(n_in, first, rest)
    flat = Flat(program(net))
    assert flat.acc_dtype is acc and flat.wflat.dtype == np.int8 and flat.shift[1] == 7
    x = np.ones((2, 6, n_in), np.uint8)
    fast = PreparedNetwork(net).run(x, record="all", threads=2)
    slow = reference_run(net, x, record="all")
    _same(fast, slow, "all")
    # q is delivered in full: the inputs of step 0 arrive at step 1 (iDecay 4096: u = q, wrapped to 22 bits)
    q = (first + (n_in - 1) * rest) * 64
    q_wrapped = ((q + 2**21) % 2**22) - 2**21
    assert fast.current[1][0, 1, 0] == q_wrapped


def test_every_network_runs_one_of_the_kernel_signatures_a_warm_cache_holds():
    """The accumulator is int16 at least and weights are int8 or the accumulator's type, so that the numba cache
    of a warm install holds the signature any network needs (a 1-neuron graph used to compile one of its own)."""
    from snncc.targets.loihi.emulation.flat import KERNEL_SIGNATURES, kernel_types

    tiny = LoihiNetwork([LoihiLayer("input", "input", 1),
                         LoihiLayer("one", "dense", 1, weight=np.array([[2]], np.int16), v_th_mant=1)], t_sample=3)
    nets = [tiny, random_network(0), random_network(1, big=True), random_network(2, split_exponents=True),
            _all_on_network(259, 254, 254)]
    for net in nets:
        flat = Flat(program(net))
        for wide in (False, True):
            state = flat.registers(wide)[-1].dtype.name
            assert (np.dtype(flat.acc_dtype).name, flat.wflat.dtype.name, state) in KERNEL_SIGNATURES
    assert kernel_types(3, -2, 2) == (np.int16, np.int8) and kernel_types(40000, -300, 300) == (np.int32, np.int32)
    assert kernel_types(2**40, -100, 100) == (np.int64, np.int8)


def test_narrowest_int_and_common_shift():
    assert [narrowest_int(-b, b) for b in (0, 127, 128, 32767, 32768, 2**31 - 1, 2**31)] == [
        np.int8, np.int8, np.int16, np.int16, np.int32, np.int32, np.int64]
    assert narrowest_int(-128, 127) is np.int8 and narrowest_int(-129, 0) is np.int16
    assert _common_shift([np.array([[64, -192], [0, 128]]), np.zeros((0, 0), np.int64)]) == 6
    assert _common_shift([np.zeros((2, 2), np.int64)]) == 0
    assert _common_shift([np.array([[3 << 40]])]) == 40


def test_q_u_in_range_rule():
    assert q_u_in_range(np.array([2**21 - 1]), np.array([0]))             # iDecay 4096: u = q
    assert not q_u_in_range(np.array([2**21]), np.array([0]))             # q itself can wrap
    assert not q_u_in_range(np.array([1]), np.array([4096]))              # iDecay 0: u accumulates
    assert q_u_in_range(np.array([2**17 - 1]), np.array([4096 - 64]))     # |u| < q_max * 4096 / 64 < 2**23
    assert not q_u_in_range(np.array([2**17]), np.array([4096 - 64]))
    assert not q_u_in_range(np.array([5, 2**17]), np.array([4096 - 64, 4096 - 64]))   # any neuron decides


@pytest.mark.parametrize("n_in, in_range", [(8, 1), (9, 0)])
def test_in_range_path_near_its_limit_is_exact(n_in, in_range):
    """All inputs on: u climbs toward q_max * 4096 / iDecay; 8 inputs stay below 2**23, 9 wrap."""
    net = _all_on_network(n_in, 254, 254, i_decay=64)
    flat = Flat(program(net))
    assert flat.in_range[1] == in_range and flat.in_range[2] == 0      # out: iDecay 0, u unbounded
    x = np.ones((2, 400, n_in), np.uint8)
    fast = PreparedNetwork(net).run(x, record="all", threads=2)
    _same(fast, reference_run(net, x, record="all"), "all")
    peak = np.abs(fast.current[1]).max()
    if in_range:
        assert 0.95 * 2**23 < peak < 2**23 and fast.overflow["u_wrap"] == 0
    else:
        assert fast.overflow["u_wrap"] > 0


def test_both_update_paths_are_exercised_by_the_random_networks():
    flags = {int(Flat(program(random_network(seed, **kw))).in_range[1])
             for seed, kw in ((20, {}), (24, {"big": True}), (26, {"profiles": True}))}
    assert flags == {0, 1}


def test_spike_list_finds_every_spike_in_order():
    rng = np.random.default_rng(3)
    spk = np.zeros(256, np.int32)
    for m in (1, 7, 8, 63, 64, 65, 130):
        for p in (0.0, 0.03, 0.5, 1.0):
            fired = np.zeros(((m + 63) & ~63) + 64, np.uint8)
            fired[:m] = rng.random(m) < p
            fired[m:] = 1                        # stale bytes past m must be ignored
            expected = np.flatnonzero(fired[:m])
            c = _spike_list(fired, m, spk)
            assert spk[:c].tolist() == expected.tolist(), (m, p)
