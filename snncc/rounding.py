"""Rounding with error feedback: coefficients to an integer grid, judged by the error their inputs see.

A neuron sees its coefficients' rounding errors e only through the sum e . z(t) over its inputs z, so
with H = E[z z^T] (the inputs' second moments) the error that matters is e^T H e, not each |e_j|.
Rounding the coefficients one at a time (largest H_jj first) and moving the ones still free to the
optimum of that quadratic form after each (the optimal-brain-quantizer update) keeps it small:

    k_i  = clip(round(c_i / step_i), low_i, high_i)           err = c_i - k_i step_i
    c_f -= Hinv_fi / Hinv_ii * err                            f: the coefficients not yet rounded
    Hinv_ff -= Hinv_fi Hinv_if / Hinv_ii                      (the inverse of H over the free ones)

Rows of a 2-D ``c`` share H and are rounded together. Where H is diagonal this is rounding to nearest.
Shared by Xylo's lowering (``targets/xylo/identify.py``) and Loihi's fine-tuning starting points
(``targets/loihi/rescale.py``).
"""

from __future__ import annotations

import numpy as np


def damped(h: np.ndarray, damping: float) -> np.ndarray:
    """H + damping * mean(diag H) * I (a tiny floor keeps an all-zero H invertible)."""
    h = np.asarray(h, np.float64)
    return h + (damping * max(float(np.mean(np.diag(h))), 0.0) + 1e-12) * np.eye(h.shape[0])


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
    order = np.array([i for i in np.argsort(-np.diag(h), kind="stable") if i != last]
                     + ([last] if last is not None else []), np.int64)
    # in rounding order, the coefficients still free are always a suffix: plain slices, no index copies
    hinv = np.linalg.inv(np.asarray(h, np.float64))[np.ix_(order, order)]
    c, step, low, high = c[:, order], step[order], low[order], high[order]
    k = np.zeros(c.shape, np.int64)
    for i in range(n):
        k[:, i] = np.clip(np.round(c[:, i] / step[i]), low[i], high[i]).astype(np.int64)
        err = c[:, i] - k[:, i] * step[i]
        if i + 1 < n:
            c[:, i + 1:] -= np.outer(err, hinv[i + 1:, i] / hinv[i, i])
            hinv[i + 1:, i + 1:] -= np.outer(hinv[i + 1:, i], hinv[i, i + 1:]) / hinv[i, i]
    out = np.zeros(c.shape, np.int64)
    out[:, order] = k
    return out[0] if one else out
