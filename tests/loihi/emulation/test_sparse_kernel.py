"""The kernel's sparse delivery (SparseBlock projections, synapse by synapse, never densified):
threads, mixed sparse and dense layers, narrow types at their limit, against the plain statement."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.targets.loihi.emulation import emulator
from snncc.targets.loihi.emulation.flat import Flat
from snncc.targets.loihi.emulation.emulator import PreparedNetwork, SparseBlock, program, reference_run
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from tests.loihi.helpers import random_network
from tests.loihi.emulation.test_kernel import _same


def _thin(net, seed, keep=0.5):
    rng = np.random.default_rng(seed)
    for lay in net.layers[1:]:
        lay.weight = np.where(rng.random(lay.weight.shape) < keep, lay.weight, 0).astype(lay.weight.dtype)
        if lay.weight_rec is not None:
            lay.weight_rec = np.where(rng.random(lay.weight_rec.shape) < keep, lay.weight_rec, 0).astype(
                lay.weight_rec.dtype)
    return net


@pytest.fixture
def sparse_from_60_synapses(monkeypatch):
    """Blocks of >= 60 entries become SparseBlocks: the hidden layer's 11 x 7 feed-forward and 11 x 11
    recurrent projections, not the 5 x 11 output layer (sparse and dense layers in one network)."""
    monkeypatch.setattr(emulator, "SPARSE_MIN_SIZE", 60)
    monkeypatch.setattr(emulator, "SPARSE_MAX_DENSITY", 1.0)


@pytest.mark.parametrize("seed, kwargs", [
    (40, {}), (41, {"per_synapse_delays": False}), (42, {"big": True}), (43, {"split_exponents": True}),
    (44, {"recurrent": False, "profiles": True}),
])
def test_sparse_threaded_equals_serial_and_the_plain_statement(sparse_from_60_synapses, seed, kwargs):
    net = _thin(random_network(seed, **kwargs), seed)
    x = (np.random.default_rng(seed).random((7, 40, net.input_width)) < 0.3).astype(np.uint8)
    prepared = PreparedNetwork(net)
    flat = prepared.flat
    assert isinstance(flat.prog.wt[1], SparseBlock) and not isinstance(flat.prog.wt[2], SparseBlock)
    assert flat.wsp[1] >= 0 and flat.wsp[2] == -1
    assert (flat.rsp[1] >= 0) == kwargs.get("recurrent", True)
    # only the synapses are stored: no dense copy of a sparse block
    nnz = sum(int(np.count_nonzero(w)) for w in (net.layers[1].weight, net.layers[1].weight_rec) if w is not None)
    assert flat.spost.size == nnz and flat.wflat.size == nnz + net.layers[2].weight.size
    for record in ("outputs", "all"):
        serial = prepared.run(x, record=record, threads=1)
        threaded = prepared.run(x, record=record, threads=3)       # 7 samples over 3 threads
        _same(threaded, serial, record)
        _same(serial, reference_run(net, x, record=record), record)
    assert serial.spikes[1].sum() > 0 and np.any(serial.current[2] != 0)   # both deliveries carry spikes
    if kwargs.get("big"):
        assert flat.in_range[1] == 0 and serial.overflow["q_wrap"] > 0
    else:
        assert flat.in_range[1] == 1


def _one_hub_network(n_in: int, weight: int) -> LoihiNetwork:
    """Hidden neuron 0 receives every input with ``weight``; neurons 1 and 2 one input each: the
    accumulator bound is a per-POST-neuron sum (a per-source sum would be 3 x smaller)."""
    w = np.zeros((3, n_in), np.int16)
    w[0] = weight
    w[1, 0] = w[2, 1] = weight
    hidden = LoihiLayer("hidden", "dense", 3, weight=w, wgt_exp=0, v_th_mant=2**17 - 1, i_decay=4096, v_decay=4096,
                        vmin=-(2**23 - 1), vmax=2**23 - 1)
    out = LoihiLayer("out", "dense", 2, weight=np.full((2, 3), 2, np.int16), v_th_mant=1)
    return LoihiNetwork([LoihiLayer("input", "input", n_in), hidden, out], t_sample=6)


@pytest.mark.parametrize("n_in, acc", [(258, np.int16), (259, np.int32)])
def test_sparse_accumulator_bound_is_per_post_neuron_and_exact_at_its_limit(monkeypatch, n_in, acc):
    monkeypatch.setattr(emulator, "SPARSE_MIN_SIZE", 3 * n_in)     # the hidden projection only
    monkeypatch.setattr(emulator, "SPARSE_MAX_DENSITY", 1.0)
    net = _one_hub_network(n_in, 254)                  # w_chip = 254 * 64 = 127 << 7
    flat = Flat(program(net))
    assert isinstance(flat.prog.wt[1], SparseBlock) and flat.prog.wt[1].w.size == n_in + 2
    assert flat.acc_dtype is acc and flat.wflat.dtype == np.int8 and flat.shift[1] == 7
    x = np.ones((2, 6, n_in), np.uint8)
    fast = PreparedNetwork(net).run(x, record="all", threads=2)
    _same(fast, reference_run(net, x, record="all"), "all")
    q = n_in * 254 * 64
    assert fast.current[1][0, 1, 0] == ((q + 2**21) % 2**22) - 2**21
    assert fast.current[1][0, 1, 1] == 254 * 64
