"""What Xylo's emulator and its numba kernel share: the result of a run."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

STATE_NAMES = ("vmem", "isyn", "isyn2", "spikes", "vmem_out", "isyn_out")


@dataclass
class XyloResult:
    """What a run gives: output event counts, and per-step states when recorded."""

    output_spikes: np.ndarray               # (B, T, Nout) uint8 output events per step (0 or 1)
    vmem: np.ndarray | None = None          # (B, T, N) int16 hidden membrane potentials
    isyn: np.ndarray | None = None          # (B, T, N) int16 hidden synaptic currents, synapse 1
    isyn2: np.ndarray | None = None         # (B, T, N) int16 hidden synaptic currents, synapse 2
    spikes: np.ndarray | None = None        # (B, T, N) uint8 hidden event counts (0 .. 31)
    vmem_out: np.ndarray | None = None      # (B, T, Nout) int16
    isyn_out: np.ndarray | None = None      # (B, T, Nout) int16
    events: dict[str, int] | None = None    # reference_run(count=True): how often each rule bit (COUNTERS)

    @property
    def recorded(self) -> bool:
        return self.vmem is not None

    @property
    def counts(self) -> np.ndarray:
        """(B, Nout) output events summed over time."""
        return self.output_spikes.sum(axis=1, dtype=np.int64)

    def arrays(self) -> dict[str, np.ndarray]:
        """The result as named arrays (what a file of results holds)."""
        out = {"output_spikes": self.output_spikes}
        if self.recorded:
            out.update({name: getattr(self, name) for name in STATE_NAMES})
        return out
