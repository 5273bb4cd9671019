"""A third-party target as an outside package would write it (installed by the tests through a
``*.dist-info/entry_points.txt``), reading nothing of snncc but ``snncc.targets.base`` and the graph:
lower writes a small JSON summary of the graph; check measures the IR reference's accuracy on the
data. It declares an option of its own (``--toy-precision``, validated by its declaration) beside
``--time-steps``, which Loihi and Jetson declare too. It has no map, emulate, run, estimate or bench."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from snncc.targets.base import TargetOptions, option, target_options


@dataclass(frozen=True)
class ToyOptions(TargetOptions):
    """The toy target takes --time-steps and its own --toy-precision."""

    time_steps: int | None = option("Steps the toy summary records.", minimum=1, capabilities=("lower",))
    toy_precision: int | None = option("Bits of the toy's weights (2..16).", minimum=2, maximum=16,
                                       rule="precision must be a whole number in [2, 16]",
                                       capabilities=("lower", "check"))


@dataclass
class ToyArtefact:
    nodes: int
    dt: float
    time_steps: int | None
    precision: int | None

    def write(self, path) -> None:
        Path(path).write_text(json.dumps(self.summary()))

    def summary(self) -> dict:
        return {"nodes": self.nodes, "dt": self.dt, "time_steps": self.time_steps, "precision": self.precision}


@dataclass
class ToyCheck:
    samples: int
    accuracy: float
    precision: int | None

    def as_dict(self) -> dict:
        return {"target": "toy", "samples": self.samples, "accuracy": self.accuracy, "precision": self.precision}

    def render_text(self, console) -> None:
        console.print(f"toy check: {self.samples} samples, accuracy {100 * self.accuracy:.1f} %")


class ToyTarget:
    name = "toy"
    description = "a test target: a JSON summary of the graph"
    output_kind = "file"
    options_type = ToyOptions

    def lower(self, graph, options=None, *, progress=None) -> ToyArtefact:
        opts = target_options(self, options, "lower")
        if progress is not None:
            progress(1, 1, "summarising")
        return ToyArtefact(len(list(graph)), float(graph.dt), opts.time_steps, opts.toy_precision)

    def identify(self, path):
        """A JSON file holding the toy summary's keys is a toy artefact (it records no source hash)."""
        from snncc.targets.kit.artefact import ArtefactIdentity

        try:
            record = json.loads(Path(path).read_text())
        except (OSError, ValueError):
            return None
        if not isinstance(record, dict) or set(record) != {"nodes", "dt", "time_steps", "precision"}:
            return None
        return ArtefactIdentity(target="toy", path=str(path), description="toy summary (JSON)")

    def check(self, graph, inputs, labels, options=None, *, artefact=None, data=None, synthetic=False,
              progress=None) -> ToyCheck:
        """The written summary must describe ``graph``; the accuracy is the IR reference's."""
        from snncc.ir.simulate import simulate

        opts = target_options(self, options, "check")
        if artefact is not None and json.loads(Path(artefact).read_text())["nodes"] != len(list(graph)):
            raise ValueError("the toy artefact describes another graph")
        prediction = np.asarray(simulate(graph, np.asarray(inputs, np.float32)).prediction)
        if progress is not None:
            progress(len(labels))
        return ToyCheck(len(labels), float(np.mean(prediction == np.asarray(labels))), opts.toy_precision)


target = ToyTarget()
