"""The emulator's sparse path (large mostly-zero projections stored as synapses per source) is
bit-exact: the same spikes, u, v and overflow counts as the dense kernel and the plain-numpy
statement of the chip's rules, with per-synapse delays, split exponents and recurrence."""

import numpy as np
import pytest

from snncc.targets.loihi.emulation import emulator
from snncc.targets.loihi.emulation.emulator import PreparedNetwork, SparseBlock, emulate, reference_run

from tests.loihi.helpers import random_network


def _sparsify(net, seed):
    rng = np.random.default_rng(seed)
    for lay in net.layers[1:]:
        lay.weight = np.where(rng.random(lay.weight.shape) < 0.5, lay.weight, 0).astype(lay.weight.dtype)
        if lay.weight_rec is not None:
            lay.weight_rec = np.where(rng.random(lay.weight_rec.shape) < 0.5, lay.weight_rec, 0).astype(
                lay.weight_rec.dtype)
    return net


@pytest.mark.parametrize("seed,kwargs", [(0, {}), (1, {"per_synapse_delays": False}), (2, {"split_exponents": True}),
                                         (3, {"big": True}), (4, {"recurrent": False, "profiles": True})])
def test_sparse_kernel_equals_dense_kernel_and_the_chip_statement(monkeypatch, seed, kwargs):
    net = _sparsify(random_network(seed, **kwargs), seed)
    x = (np.random.default_rng(seed + 10).random((3, 40, net.input_width)) < 0.3).astype(np.uint8)
    dense = emulate(net, x, record="all")
    monkeypatch.setattr(emulator, "SPARSE_MIN_SIZE", 0)
    monkeypatch.setattr(emulator, "SPARSE_MAX_DENSITY", 1.0)
    prepared = PreparedNetwork(net)
    assert all(isinstance(w, SparseBlock) for w in prepared.flat.prog.wt[1:])
    sparse = prepared.run(x, record="all")
    plain = reference_run(net, x, record="all")
    assert sum(int(dense.spikes[i].sum()) for i in range(1, len(net.layers))) > 0
    for other in (dense, plain):
        assert sparse.overflow == other.overflow
        for i in sparse.spikes:
            np.testing.assert_array_equal(sparse.spikes[i], other.spikes[i])
            if i:
                np.testing.assert_array_equal(sparse.voltage[i], other.voltage[i])
                np.testing.assert_array_equal(sparse.current[i], other.current[i])
