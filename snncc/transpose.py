"""A large matrix transposed into C order in blocks of rows.

numpy copies a whole transposed view element by element across the full matrix, which is cache-bound: for a
(8192, 992) float64 matrix 0.11-0.2 s, against 0.035 s copying 256 rows at a time (each block's rows are read
contiguously and land in the columns of the output while they are still in cache).
"""

from __future__ import annotations

import numpy as np

TRANSPOSE_ROWS = 256    # rows of the input copied at a time


def transposed(a: np.ndarray, factor: float = 1.0, dtype=None) -> np.ndarray:
    """(a * factor).T as a new C-contiguous array (``dtype``: the output's, default a's), copied in blocks of rows;
    ``factor`` 1 multiplies nothing."""
    out = np.empty(a.shape[::-1], a.dtype if dtype is None else dtype)
    for r0 in range(0, a.shape[0], TRANSPOSE_ROWS):
        block = a[r0:r0 + TRANSPOSE_ROWS]
        out[:, r0:r0 + TRANSPOSE_ROWS] = (block * factor if factor != 1.0 else block).T
    return out
