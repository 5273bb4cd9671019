"""The lowering's inner loops compiled (numba): the same floating-point operations, in the same order, as the
numpy code they replace, so every value is identical.

    synaptic(z, a, out)    out[s, t] = a (out[s, t-1] + z[s, t])     Xylo's synapse: input added before the decay
    membrane(z, b, out)    out[s, t] = b out[s, t-1] + z[s, t]       a leaky sum
    gather_scaled(block, rows, w, out)   out[i] = block[rows[i]] * w[i]: a neuron's weighted regression rows, in
                                         one pass into a buffer that is reused

``z``: (samples, steps, channels) spike trains (uint8) or float64 traces; ``out``: (samples * steps, channels)
float64 rows (a view into a feature block may be strided). Explicit signatures, compiled once and cached on disk
(``cache=True``): a warm install compiles nothing. ``numba`` is imported only here, under
``kit.compute.sigint_deferred``, when the lowering first filters.
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit.compute import sigint_deferred

with sigint_deferred():   # numba's C init would turn a Ctrl-C into an ImportError (kit.compute)
    from numba import njit

_SIGNATURES = ["void(uint8[:, :, ::1], float64, float64[:, :])", "void(float64[:, :, ::1], float64, float64[:, :])"]


@njit(_SIGNATURES, cache=True, nogil=True)
def _synaptic(z, a, out):
    samples, steps, channels = z.shape
    acc = np.zeros(channels)
    for s in range(samples):
        acc[:] = 0.0
        for t in range(steps):            # the channels innermost: z's and out's rows are read in order
            row = s * steps + t
            for c in range(channels):
                acc[c] = a * (acc[c] + z[s, t, c])
                out[row, c] = acc[c]


@njit(_SIGNATURES, cache=True, nogil=True)
def _membrane(z, b, out):
    samples, steps, channels = z.shape
    acc = np.zeros(channels)
    for s in range(samples):
        acc[:] = 0.0
        for t in range(steps):
            row = s * steps + t
            for c in range(channels):
                acc[c] = b * acc[c] + z[s, t, c]
                out[row, c] = acc[c]


def _contiguous(z: np.ndarray) -> np.ndarray:
    z = np.asarray(z)
    return np.ascontiguousarray(z if z.dtype in (np.uint8, np.float64) else z.astype(np.float64))


def synaptic(z: np.ndarray, a: float, out: np.ndarray | None = None) -> np.ndarray:
    """Rows (samples * steps, channels) of F[t] = a (F[t-1] + z[t]) per sample and channel (into ``out``)."""
    z = _contiguous(z)
    if out is None:
        out = np.empty((z.shape[0] * z.shape[1], z.shape[2]), np.float64)
    _synaptic(z, float(a), out)
    return out


def membrane(z: np.ndarray, b: float, out: np.ndarray | None = None) -> np.ndarray:
    """Rows (samples * steps, channels) of G[t] = b G[t-1] + z[t] per sample and channel (into ``out``)."""
    z = _contiguous(z)
    if out is None:
        out = np.empty((z.shape[0] * z.shape[1], z.shape[2]), np.float64)
    _membrane(z, float(b), out)
    return out


@njit(["void(float64[:, ::1], int64[::1], float64[::1], float64[:, ::1])"], cache=True, nogil=True)
def _gather_scaled(block, rows, w, out):
    for i in range(rows.size):
        r = rows[i]
        wi = w[i]
        for c in range(block.shape[1]):
            out[i, c] = block[r, c] * wi


def gather_scaled(block: np.ndarray, rows: np.ndarray, w: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out[:len(rows)] = block[rows] * w[:, None]`` (the first ``len(rows)`` rows of ``out``, returned)."""
    n = rows.size
    _gather_scaled(block, np.ascontiguousarray(rows, np.int64), np.ascontiguousarray(w, np.float64), out)
    return out[:n]
