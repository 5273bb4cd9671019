"""What every ``Emulation`` derives from its output spikes (``snncc.targets.base.Emulation``).

    samples, steps = output_spikes.shape[:2]          (B, T, N) uint8
    counts         = output_spikes summed over time    (B, N) int64
    prediction     = argmax of counts, ties to the lowest index   (B,) int64
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class OutputSpikes:
    """A run's output spikes (B, T, N) and what follows from them; a target's emulation result extends it."""

    output_spikes: np.ndarray

    @property
    def samples(self) -> int:
        return int(self.output_spikes.shape[0])

    @property
    def steps(self) -> int:
        return int(self.output_spikes.shape[1])

    @property
    def counts(self) -> np.ndarray:
        return self.output_spikes.sum(axis=1, dtype=np.int64)

    @property
    def prediction(self) -> np.ndarray:
        return _argmax(self.counts)

    def output_arrays(self) -> dict[str, np.ndarray]:
        """``output_spikes``, ``counts`` and ``prediction``: what every emulation's ``arrays()`` holds first (the
        counts summed once)."""
        counts = self.counts
        return {"output_spikes": self.output_spikes, "counts": counts, "prediction": _argmax(counts)}


def _argmax(counts: np.ndarray) -> np.ndarray:
    """Per sample the output with the most spikes, ties to the lowest index."""
    return np.argmax(counts, axis=1).astype(np.int64)
