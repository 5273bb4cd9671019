"""The recursive filters of the lowering's regression, compiled (numba): the same floating-point operations, in the
same order, as the numpy loops they replace, so every value is identical.

    synaptic(z, a, out)    out[s, t] = a (out[s, t-1] + z[s, t])     Xylo's synapse: input added before the decay
    membrane(z, b, out)    out[s, t] = b out[s, t-1] + z[s, t]       a leaky sum

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
    for s in range(samples):
        for c in range(channels):
            acc = 0.0
            for t in range(steps):
                acc = a * (acc + z[s, t, c])
                out[s * steps + t, c] = acc


@njit(_SIGNATURES, cache=True, nogil=True)
def _membrane(z, b, out):
    samples, steps, channels = z.shape
    for s in range(samples):
        for c in range(channels):
            acc = 0.0
            for t in range(steps):
                acc = b * acc + z[s, t, c]
                out[s * steps + t, c] = acc


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
