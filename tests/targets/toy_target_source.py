"""A third-party target as an outside package would write it (installed by the tests through a
``*.dist-info/entry_points.txt``): lower writes a small JSON summary of the graph; check measures
the IR reference's accuracy on the data. It has no map, emulate, run, estimate or bench."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from snncc.targets.base import TargetOptions, target_options


@dataclass(frozen=True)
class ToyOptions(TargetOptions):
    """The toy target takes --time-steps only."""

    time_steps: int | None = None


@dataclass
class ToyArtefact:
    nodes: int
    dt: float
    time_steps: int | None

    def write(self, path) -> None:
        Path(path).write_text(json.dumps(self.summary()))

    def summary(self) -> dict:
        return {"nodes": self.nodes, "dt": self.dt, "time_steps": self.time_steps}


@dataclass
class ToyCheck:
    samples: int
    accuracy: float

    def as_dict(self) -> dict:
        return {"target": "toy", "samples": self.samples, "accuracy": self.accuracy}

    def render_text(self, console) -> None:
        console.print(f"toy check: {self.samples} samples, accuracy {100 * self.accuracy:.1f} %")


class ToyTarget:
    name = "toy"
    description = "a test target: a JSON summary of the graph"
    output_kind = "file"
    options_type = ToyOptions

    def lower(self, graph, options=None, *, progress=None) -> ToyArtefact:
        opts = target_options(self, options)
        return ToyArtefact(len(list(graph)), float(graph.dt), opts.time_steps)

    def check(self, graph, inputs, labels, options=None, *, data=None, synthetic=False, progress=None) -> ToyCheck:
        from snncc.ir.simulate import simulate

        target_options(self, options)
        prediction = simulate(graph, np.asarray(inputs, np.float32)).prediction.numpy()
        if progress is not None:
            progress(len(labels))
        return ToyCheck(len(labels), float(np.mean(prediction == np.asarray(labels))))


target = ToyTarget()
