"""What the emulator and its numba kernel share: the result of a run (``EmulationResult``, prediction =
argmax of the output counts, ties to the lowest index) and a projection's synapses grouped by source
(``SparseBlock``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class EmulationResult:
    output_spikes: np.ndarray                          # (B, T, n_out) uint8
    counts: np.ndarray                                 # (B, n_out) int64
    prediction: np.ndarray                             # (B,) int64, argmax with ties to the lowest index
    spikes: dict[int, np.ndarray] = field(default_factory=dict)    # layer index -> (B, T, n) uint8
    voltage: dict[int, np.ndarray] = field(default_factory=dict)   # layer index -> (B, T, n) post-reset v
    current: dict[int, np.ndarray] = field(default_factory=dict)   # layer index -> (B, T, n) u
    overflow: dict[str, int] = field(default_factory=lambda: {"q_wrap": 0, "u_wrap": 0, "v_clip": 0})


def _prediction(counts: np.ndarray) -> np.ndarray:
    return np.argmax(counts, axis=1).astype(np.int64)  # numpy argmax returns the first maximum


@dataclass
class SparseBlock:
    """A projection's synapses grouped by source neuron (what the chip stores per input axon):
    synapses ptr[k]..ptr[k+1]-1 of source k go to ``post`` with chip weight ``w`` and delay ``delay``."""

    n_pre: int
    n_post: int
    ptr: np.ndarray          # (n_pre + 1,) int64
    post: np.ndarray         # (nnz,) int64
    w: np.ndarray            # (nnz,) int64, chip units
    delay: np.ndarray        # (nnz,) int64

    def dense_transposed(self) -> tuple[np.ndarray, np.ndarray]:
        """(weights, delays) as dense (n_pre, n_post) int64 arrays, zeros where there is no synapse
        (for comparisons with dense code, e.g. an earlier kernel; the kernel itself never densifies)."""
        pre = np.repeat(np.arange(self.n_pre), np.diff(self.ptr))
        w = np.zeros((self.n_pre, self.n_post), np.int64)
        uniform = self.delay.size and np.all(self.delay == self.delay[0])
        d = np.full((self.n_pre, self.n_post), int(self.delay[0]) if uniform else 0, np.int64)
        w[pre, self.post] = self.w
        d[pre, self.post] = self.delay
        return w, d
