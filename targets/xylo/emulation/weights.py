"""The weights a delivery adds on Xylo's v2 core, shared by the emulator and its numba kernel: w << shift
narrowed to the state width (two's complement: it wraps, never saturates)."""

from __future__ import annotations

import numpy as np

from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.spec import XyloSpec


def wrap16(x):
    """Two's complement narrowing to the state width (``CORE.state_bits``), elementwise on int64."""
    half = np.int64(1) << (CORE.state_bits - 1)
    return ((np.asarray(x, np.int64) + half) & (2 * half - 1)) - half


def _shifted(spec: XyloSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """w << shift (int64, before narrowing) for the three matrices, shaped (Nin, N_ien, 2), (N, N, 2)
    and (N_oen, Nout); an absent synapse axis means synapse 1 only (zeros on synapse 2)."""
    def both_synapses(w):
        w = w if w.ndim == 3 else w[:, :, None]
        pad = np.zeros(w.shape[:2] + (CORE.hidden_synapse_states - w.shape[2],), np.int64)
        return np.concatenate([w.astype(np.int64), pad], axis=2)

    return (both_synapses(spec.weights_in) << spec.weight_shift_in,
            both_synapses(spec.weights_rec) << spec.weight_shift_rec,
            spec.weights_out.astype(np.int64) << spec.weight_shift_out)


def effective_weights(spec: XyloSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The weights a delivery adds: int16(w << shift) (wraps, never saturates), shapes as ``_shifted``."""
    return tuple(wrap16(w) for w in _shifted(spec))


def wrapped_weights(spec: XyloSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True where w << shift does not fit int16 and wraps (shapes as ``effective_weights``)."""
    return tuple(w != wrap16(w) for w in _shifted(spec))
