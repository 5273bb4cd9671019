"""The float graph on a user's inputs (``snncc emulate MODEL``): the IR reference simulator, as an emulation.

The same .npz layout as every target's emulator, so predictions line up sample by sample:
``output_spikes`` (B, T, N) uint8 (the readout population's spikes; a non-spiking readout writes its
``scores`` (B, N) instead), ``counts`` (B, N), ``prediction`` (B,) (ties to the lowest index); with
``record="all"`` also ``<population>_spikes``, ``<population>_voltage`` and ``<population>_current`` of
every LIF population (float64, as the reference simulator records them). The run is float64, on the
model as loaded with the model options (dt, reset, params): what every artefact is checked against.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from snncc.errors import SnnccError

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

CHUNK_NOTE = "float64, the IR reference simulator (snncc.ir.simulate): the definition every artefact is checked against"


@dataclass
class FloatEmulation:
    """The reference run's arrays (``snncc.targets.base.Emulation``)."""

    output_spikes: np.ndarray | None
    scores: np.ndarray
    states: dict[str, np.ndarray] = field(default_factory=dict)
    input_note: str | None = None

    @property
    def samples(self) -> int:
        return int(self.scores.shape[0])

    @property
    def steps(self) -> int:
        return int(self.output_spikes.shape[1]) if self.output_spikes is not None else 0

    @property
    def prediction(self) -> np.ndarray:
        return np.argmax(self.scores, axis=1).astype(np.int64)

    def arrays(self) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        if self.output_spikes is not None:
            out["output_spikes"] = self.output_spikes
            out["counts"] = self.scores.astype(np.int64)
        else:
            out["scores"] = self.scores
        return {**out, "prediction": self.prediction, **self.states}

    def summary(self) -> dict[str, object]:
        return {"reference": CHUNK_NOTE, "input_layout": self.input_note}

    def lines(self) -> list[str]:
        out = [f"input: {self.input_note}"] if self.input_note else []
        return out + [f"the float graph: {CHUNK_NOTE}"]

    def warnings(self) -> list[str]:
        return []


def run_float(graph: Graph, inputs: np.ndarray, *, record: str = "outputs", source: str | None = None,
              progress: Callable[[int], None] | None = None) -> FloatEmulation:
    """The float graph on ``inputs`` (T, C), (B, T, C) or the model's own shape (input copies, CNN frames)."""
    from snncc.input_layout import graph_layout, to_artefact_layout
    from snncc.inputs import check_batch
    from snncc.ir.nodes import LIF, Readout
    from snncc.ir.simulate import simulate
    from snncc.measure.agreement import chunk_size
    from snncc.threads import one_thread

    layout = graph_layout(graph)
    x, note = to_artefact_layout(inputs, layout)
    x = check_batch(x, layout.width, spikes=False, source=source, field="--input")
    lifs = [n for n, op in graph.items() if isinstance(op, LIF)]
    readout = next((n for n, op in graph.items() if isinstance(op, Readout)), None)
    # a spiking graph decides by its last population's spike counts (a spike_count readout or none)
    spiking_out = bool(lifs) and (readout is None or getattr(graph.node(readout), "mode", "") == "spike_count")
    neurons = int(sum(int(getattr(graph.node(p), "n")) for p in lifs))
    step = chunk_size(max(1, neurons), int(x.shape[1]), 64)
    spikes, scores = [], []
    states: dict[str, list[np.ndarray]] = {}
    with one_thread():
        for start in range(0, x.shape[0], step):
            part = x[start:start + step]
            res = simulate(graph, part, record="all" if record == "all" else "spikes")
            if spiking_out:
                s = np.asarray(res.spikes[lifs[-1]]).astype(np.uint8)
                spikes.append(s)
                scores.append(s.sum(axis=1, dtype=np.int64))
            else:
                scores.append(np.asarray(res.readout if res.readout is not None else res.output[:, -1]))
            if record == "all":
                for name in lifs:
                    for what, table in (("spikes", res.spikes), ("voltage", res.voltage), ("current", res.current)):
                        if name in table:
                            states.setdefault(f"{name}_{what}", []).append(np.asarray(table[name]))
            if progress is not None:
                progress(int(part.shape[0]))
    if not scores:
        raise SnnccError("the input holds no sample", file=source, field="--input")
    joined = {k: np.concatenate(v) for k, v in states.items()}
    return FloatEmulation(np.concatenate(spikes) if spikes else None, np.concatenate(scores), joined, note)
