"""The mapper reads a dense projection's nonzero pattern in blocks of rows (``projections._dense_pattern``): the same
index arrays scipy's CSR of the matrix has, a full matrix reported as full, explicit zeros left out."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from snncc.targets.loihi.mapping import projections


@pytest.mark.parametrize("rows, cols, density", [(7, 5, 0.5), (300, 40, 0.9), (1, 1, 0.0), (50, 3, 0.0)])
def test_the_pattern_is_scipys(monkeypatch, rows, cols, density):
    monkeypatch.setattr(projections, "PATTERN_BLOCK", 64)          # several blocks even for small matrices
    rng = np.random.default_rng(rows)
    w = np.where(rng.random((rows, cols)) < density, rng.integers(-5, 6, (rows, cols)), 0)
    full, csr = projections._nonzeros(w, (rows, cols), "layer")
    expected = sp.csr_matrix(w)
    expected.eliminate_zeros()
    assert not full
    assert np.array_equal(csr.indptr, expected.indptr) and np.array_equal(csr.indices, expected.indices)
    assert csr.has_sorted_indices and csr.nnz == np.count_nonzero(w)


def test_a_full_matrix_is_full():
    assert projections._nonzeros(np.ones((4, 6)), (4, 6), "layer") == (True, None)
