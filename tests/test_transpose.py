"""``snncc.transpose.transposed``: the transpose, scaled, in C order, whatever the block size."""

from __future__ import annotations

import numpy as np
import pytest

import snncc.transpose
from snncc.transpose import transposed


@pytest.mark.parametrize("rows", [1, 3, 256])
def test_blocks_give_the_transpose(monkeypatch, rows):
    monkeypatch.setattr(snncc.transpose, "TRANSPOSE_ROWS", rows)
    a = np.random.default_rng(rows).normal(size=(11, 7))
    for factor in (1.0, 0.5):
        out = transposed(a, factor)
        assert out.flags.c_contiguous and out.dtype == a.dtype and np.array_equal(out, (a * factor).T)
    assert transposed(a, dtype=np.float32).dtype == np.float32
    assert transposed(np.zeros((0, 4))).shape == (4, 0)
