"""``snncc run``'s work: a Jetson artefact run on inputs (TensorRT where importable, else ONNX Runtime).

The results hold ``output_spikes`` (B, T, n) uint8, ``counts`` (B, n) and ``prediction`` (B,) for
SNNs (the ``snncc emulate`` contract), ``scores`` (B, n) and ``prediction`` for LSTMs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError


def open_runner(artefact: Path, backend: str, variant: str | None = None):
    """An ``ArtefactRunner`` on the artefact directory, with ``variant``'s model already loaded (so
    that a damaged model file is named as part of the artefact), or a one-line error (another kind of
    artefact, a Loihi bundle say, is named with the command that reads it)."""
    from snncc.targets.jetson.manifest import JETSON_FORMAT
    from snncc.targets.jetson.standalone_runner import ArtefactRunner, RunnerError

    JETSON_FORMAT.open(artefact)          # a Jetson artefact whose files are regular files inside it, else one line
    try:
        runner = ArtefactRunner(str(artefact), backend)
        if variant is not None:
            runner.session(variant)
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(artefact), field=ex.field) from None
    _record_own_files(Path(artefact), runner.manifest)
    return runner


def _record_own_files(artefact: Path, manifest: dict) -> None:
    """The artefact's own files are inputs of the running command: no output may replace them."""
    from snncc.targets.kit.writing import record_input
    from snncc.targets.jetson.manifest import own_names

    for name in own_names(manifest):
        record_input(artefact / name)


@dataclass
class ArtefactRun:
    """What one run produced: the output arrays and how they were computed."""

    outputs: dict[str, np.ndarray]
    backend: str
    stream: bool
    time_steps: int
    class_names: list[str]
    input_note: str | None = None     # what was done to take the inputs in the model's own shape

    def arrays(self) -> dict[str, np.ndarray]:
        return self.outputs

    def as_dict(self) -> dict[str, Any]:
        prediction = self.outputs["prediction"].tolist()
        names = self.class_names
        return {"backend": self.backend, "variant": "step (streaming)" if self.stream else "sequence",
                "samples": int(self.outputs["prediction"].shape[0]), "time_steps": self.time_steps,
                "prediction": prediction,
                "classes": [names[i] if 0 <= i < len(names) else str(i) for i in prediction],
                "input_layout": self.input_note}


def run_artefact(artefact: Path, inputs, *, source: str | None = None, stream: bool = False,
                 backend: str = "auto") -> ArtefactRun:
    """Check ``inputs`` (T, C) or (B, T, C) -- or CNN frames (B, T, C, H, W), flattened -- against the
    artefact's input signal and run the sequence model, or with ``stream`` the step model one step at a time."""
    from snncc.targets.kit.inputs import check_batch
    from snncc.targets.jetson.standalone_runner import RunnerError

    from snncc.targets.kit.inputs import InputLayout, to_artefact_layout

    runner = open_runner(artefact, backend, "step" if stream else "sequence")
    spec = runner.manifest["input"]
    inputs, note = to_artefact_layout(inputs, InputLayout(width=int(spec["channels"]),
                                                          frame=tuple(spec["frame_shape"]) if spec.get("frame_shape")
                                                          else None))
    x = check_batch(inputs, spikes=spec["signal"] == "spikes", source=source)
    try:
        res = runner.stream(x) if stream else runner.run(x)
        used = runner.session("step" if stream else "sequence").backend
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=source, field=ex.field) from None
    return ArtefactRun(res, used, stream, int(np.asarray(x).shape[-2]), list(runner.manifest["classes"]), note)
