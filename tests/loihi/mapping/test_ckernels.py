"""The partitioner's C kernels (mapping/kernels.c) give the numba kernels' integers, and ``map_network`` the same
core map with either."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from snncc.targets.loihi.mapping import kernels, numba_kernels
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.native import VARIABLE
from snncc_test_helpers import need_c_compiler
from tests.loihi.helpers import random_network


def _pattern(seed, n_rows, n_cols, density):
    csr = sp.random(n_rows, n_cols, density=density, format="csr", random_state=seed)
    return csr.indptr.astype(np.int64), csr.indices.astype(np.int32)


@pytest.mark.parametrize("seed, n_rows, n_cols, density", [(0, 40, 30, 0.2), (1, 1, 500, 0.5), (2, 300, 7, 0.9),
                                                           (3, 50, 60, 0.0), (4, 200, 200, 0.03)])
def test_the_c_kernels_give_the_numba_kernels_integers(monkeypatch, seed, n_rows, n_cols, density):
    need_c_compiler()
    monkeypatch.setenv(VARIABLE, "c")
    indptr, indices = _pattern(seed, n_rows, n_cols, density)
    cptr, cidx = kernels.transpose_indices(indptr, indices, n_cols)
    want_ptr, want_idx = numba_kernels.transpose_indices(indptr, indices, n_cols)
    assert cptr.dtype == want_ptr.dtype and cidx.dtype == want_idx.dtype
    assert np.array_equal(cptr, want_ptr) and np.array_equal(cidx, want_idx)
    rng = np.random.default_rng(seed)
    slice_of = np.sort(rng.integers(0, 5, n_rows)).astype(np.int64)
    assert np.array_equal(kernels.distinct_per_source(cptr, cidx, slice_of),
                          numba_kernels.distinct_per_source(cptr, cidx, slice_of))
    n_cores = 6
    cores_dst = np.sort(rng.integers(0, n_cores, n_rows)).astype(np.int64)
    m_core = np.bincount(cores_dst, minlength=n_cores).astype(np.int64)
    table = rng.integers(0, 1000, (n_rows + 1, n_rows + 1)).astype(np.int64)
    src_core = rng.integers(-1, n_cores, n_cols).astype(np.int64)
    got = kernels.pair_usage(cptr, cidx, cores_dst, m_core, table, src_core, n_cores)
    want = numba_kernels.pair_usage(cptr, cidx, cores_dst, m_core, table, src_core, n_cores)
    for a, b in zip(got, want):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_core_map_is_the_same_with_either_kernel(monkeypatch, seed):
    need_c_compiler()
    net = random_network(seed, recurrent=bool(seed))
    maps = {}
    for how in ("c", "numba"):
        monkeypatch.setenv(VARIABLE, how)
        cmap = map_network(net)
        maps[how] = (cmap.n_cores, [(c.usage.neurons, c.usage.input_axons, c.usage.output_axons, c.usage.synapse_bits)
                                    for c in cmap.cores])
    assert maps["c"] == maps["numba"]
