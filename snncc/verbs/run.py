"""``snncc run``: run a written artefact on inputs (Jetson: TensorRT where importable, else ONNX Runtime).

The saved .npz holds ``output_spikes`` (B, T, n) uint8, ``counts`` (B, n) and ``prediction`` (B,) for
SNNs (the ``snncc emulate`` contract), ``scores`` (B, n) and ``prediction`` for LSTMs.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from snncc.errors import one_line

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.targets.base import RunResult


@dataclass
class RunRecord:
    artefact: str
    result: RunResult        # the target's run (as_dict: backend, variant, samples, time_steps, prediction, classes)
    output: str | None = None

    def as_dict(self) -> dict[str, object]:
        return {"artefact": self.artefact, **self.result.as_dict(), "output": self.output}

    def render_text(self, console: Console) -> None:
        r = self.result.as_dict()
        classes = r["classes"]
        assert isinstance(classes, list)
        if r.get("input_layout"):
            console.print(f"input: {r['input_layout']}", markup=False)
        console.print(f"{r['variant']} on {r['backend']}: {r['samples']} sample(s) x {r['time_steps']} steps")
        console.print("predictions: " + " ".join(str(c) for c in classes[:20]) + (" ..." if len(classes) > 20 else ""))
        if self.output is not None:
            console.print(f"wrote {one_line(self.output)}", markup=False)


def run_artefact(artefact: str | Path, *, input: str | Path, target: str | None = None, stream: bool = False,
                 output: str | Path | None = None, backend: str = "auto") -> RunRecord:
    """Run ``artefact`` on ``input`` (.npy (T, C) or (B, T, C), or a data-set .npz's inputs): the whole
    sequence model, or with ``stream`` the step model one step at a time; ``output`` saves the arrays. The target
    is the artefact's (``target``, when given, must agree with it)."""
    import numpy as np

    from snncc.atomic import atomic_path
    from snncc.inputs import load_array
    from snncc.artefacts import target_for
    from snncc.targets import capability

    run = capability(target_for(artefact, target, "run"), "run")
    result = run(Path(artefact), load_array(input), source=str(input), stream=stream, backend=backend)
    if output is not None:
        save: Callable[..., None] = np.savez       # its keywords are array names here, never allow_pickle
        with atomic_path(output) as tmp:
            with open(tmp, "wb") as fh:  # a file object: savez must not append '.npz' to the temp name
                save(fh, **result.arrays())
    return RunRecord(str(artefact), result, None if output is None else str(output))
