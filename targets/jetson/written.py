"""A written Jetson artefact opened for measurement (the Jetson target's ``identify``, and what
``snncc check`` runs): the directory's manifest and the ONNX models it lists, run in ONNX Runtime.

An artefact is a directory whose ``manifest.json`` has format ``snncc-jetson-artefact``; its files
are the manifest, the model files its variants list (``model.onnx``, ``step.onnx``) and the recipe
and runner snncc writes beside them (``build_engine.sh``, ``run.py``); TensorRT engines built on the
board (``*.plan``) are not part of it. Inputs as long as the unrolled sequence model's T run
through ``model.onnx``; any other length through ``step.onnx``, one step at a time (the record says
which ran).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from snncc.targets.jetson.artefact_format import JETSON_FORMAT, listed_files
from snncc.targets.kit import SnnccError
from snncc.targets.kit.artefact import ArtefactIdentity


def artefact_files(manifest: dict) -> list[str]:
    """The artefact's own files, as named by its manifest (sorted)."""
    return sorted(listed_files(manifest))


def identify_directory(path: str | Path) -> ArtefactIdentity | None:
    """The artefact's identity, or None when ``path`` is no directory with an snncc Jetson manifest."""
    return JETSON_FORMAT.identify(path)


@dataclass
class WrittenJetson:
    """The directory's manifest and an ONNX Runtime runner on its files."""

    directory: str
    manifest: dict
    ran: set = field(default_factory=set)        # which variants ran ("model.onnx", "step.onnx")

    @classmethod
    def open(cls, path: str | Path) -> "WrittenJetson":
        """The artefact at ``path``: every file its manifest lists a regular file inside it (else one line)."""
        return cls(str(path), JETSON_FORMAT.open(path))

    @property
    def runner(self):
        from snncc.targets.jetson.run_artefact import open_runner

        if not hasattr(self, "_runner"):
            self._runner = open_runner(Path(self.directory), "onnxruntime")
        return self._runner

    @property
    def time_steps(self) -> int:
        return int(self.manifest["time_steps"])

    def run(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(score (B, classes), output sequence (B, T, n) or None) of the written models on ``x`` (B, T, C)."""
        from snncc.targets.jetson.standalone_runner import RunnerError

        m = self.manifest
        fixed = m["time_axis"] != "dynamic"
        try:
            if fixed and x.shape[1] != self.time_steps:
                if not any(v.get("name") == "step" for v in m["variants"]):
                    raise SnnccError(f"the data have {x.shape[1]} time steps; this artefact takes exactly "
                                     f"{self.time_steps} and has no step model", file=self.directory, field="inputs")
                res = self.runner.stream(x)
                self.ran.add("step.onnx")
            else:
                res = self.runner.run(x)
                self.ran.add("model.onnx")
        except RunnerError as ex:
            raise SnnccError(ex.rule, file=self.directory, field=ex.field) from None
        score_name = m["readout"]["score_output"]
        seq = next((v for k, v in res.items() if k not in (score_name, "prediction")), None)
        return np.asarray(res[score_name], np.float64), (None if seq is None else np.asarray(seq))

    def variants_ran(self) -> str:
        return " and ".join(sorted(self.ran)) or "nothing"
