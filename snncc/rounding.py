"""Rounding with error feedback: coefficients to an integer grid, judged by the error their inputs see.

A neuron sees its coefficients' rounding errors e only through the sum e . z(t) over its inputs z, so
with H = E[z z^T] (the inputs' second moments) the error that matters is e^T H e, not each |e_j|.
Rounding the coefficients one at a time (largest H_jj first) and moving the ones still free to the
optimum of that quadratic form after each (the optimal-brain-quantizer update) keeps it small.

Computed without an inverse: with H = L^T L (L lower triangular in the rounding order: the Cholesky
factor of H with rows and columns reversed), row i of L(c - x) involves only the coefficients up to i,
so once coefficients 0 .. i-1 are fixed the free ones that minimise e^T H e zero every later row, and
coefficient i's optimum given the fixed ones is

    t_i = c_i + (sum_{j<i} L_ij e_j) / L_ii,     k_i = clip(round(t_i / step_i), low_i, high_i),
    e_i = c_i - k_i step_i                        (e: the errors of the rounded coefficients, c as given)

which is the same sequence of roundings as updating the inverse of H over the free coefficients after
each (one Cholesky factorisation, n^3 / 3, then O(n^2); no inverse, no rank-one updates). Rows of a 2-D
``c`` share H and are rounded together. Where H is diagonal this is rounding to nearest. A form that is
not positive definite (no Cholesky factor) is rounded through its pseudo-inverse by the update above.
Shared by Xylo's lowering (``targets/xylo/lowering/integers.py``) and Loihi's fine-tuning starting points
(``targets/loihi/rescale.py``).
"""

from __future__ import annotations

import numpy as np


def damped(h: np.ndarray, damping: float) -> np.ndarray:
    """H + damping * mean(diag H) * I (a tiny floor keeps an all-zero H invertible)."""
    h = np.asarray(h, np.float64)
    return h + (damping * max(float(np.mean(np.diag(h))), 0.0) + 1e-12) * np.eye(h.shape[0])


def reversed_cholesky(h: np.ndarray) -> np.ndarray:
    """L lower triangular with H = L^T L (the Cholesky factor of H with its order reversed); LinAlgError when H is
    not positive definite."""
    c = np.linalg.cholesky(np.ascontiguousarray(h[::-1, ::-1]))
    return np.ascontiguousarray(c.T[::-1, ::-1])


def round_with_feedback(h: np.ndarray, c: np.ndarray, step, low=-128, high=127,
                        last: int | None = None) -> np.ndarray:
    """Integers k (in [low, high], scalars or per coefficient) with k * step ~ c, rounded one at a time
    (largest curvature first, ``last`` at the end) with the module's feedback. ``c``: (n,) or (rows, n)
    sharing ``h`` (n, n); returns int64 of ``c``'s shape."""
    c = np.asarray(c, np.float64)
    one = c.ndim == 1
    c = np.array(c, ndmin=2)
    n = c.shape[1]
    step = np.broadcast_to(np.asarray(step, np.float64), (n,))
    low, high = np.broadcast_to(low, (n,)), np.broadcast_to(high, (n,))
    h = np.asarray(h, np.float64)
    order = np.array([i for i in np.argsort(-np.diag(h), kind="stable") if i != last]
                     + ([last] if last is not None else []), np.int64)
    hp = h[np.ix_(order, order)]
    c, step, low, high = c[:, order], step[order], low[order], high[order]
    try:
        factor = reversed_cholesky(hp)
    except np.linalg.LinAlgError:
        k = _by_inverse_updates(hp, c, step, low, high)
    else:
        k = _by_factor(factor, c, step, low, high)
    out = np.zeros(c.shape, np.int64)
    out[:, order] = k
    return out[0] if one else out


def _by_factor(factor: np.ndarray, c: np.ndarray, step, low, high) -> np.ndarray:
    """The module's rule with H = L^T L (``factor`` L, in rounding order)."""
    n = c.shape[1]
    k = np.zeros(c.shape, np.int64)
    err = np.zeros(c.shape, np.float64)
    for i in range(n):
        target = c[:, i] + (err[:, :i] @ factor[i, :i]) / factor[i, i] if i else c[:, i]
        k[:, i] = np.clip(np.round(target / step[i]), low[i], high[i]).astype(np.int64)
        err[:, i] = c[:, i] - k[:, i] * step[i]
    return k


def _by_inverse_updates(h: np.ndarray, c: np.ndarray, step, low, high) -> np.ndarray:
    """The same roundings for a form without a Cholesky factor: the pseudo-inverse over the free coefficients,
    updated after each."""
    n = c.shape[1]
    c = c.copy()
    hinv = np.linalg.pinv(h)
    k = np.zeros(c.shape, np.int64)
    for i in range(n):
        k[:, i] = np.clip(np.round(c[:, i] / step[i]), low[i], high[i]).astype(np.int64)
        err = c[:, i] - k[:, i] * step[i]
        if i + 1 < n and hinv[i, i] != 0:
            c[:, i + 1:] -= np.outer(err, hinv[i + 1:, i] / hinv[i, i])
            hinv[i + 1:, i + 1:] -= np.outer(hinv[i + 1:, i], hinv[i, i + 1:]) / hinv[i, i]
    return k
