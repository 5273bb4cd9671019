"""``snncc run``: run a Jetson artefact (TensorRT where importable, else ONNX Runtime).

``OUT.npz`` holds ``output_spikes`` (B, T, n) uint8, ``counts`` (B, n) and ``prediction`` (B,) for
SNNs (the ``snncc emulate`` contract), ``scores`` (B, n) and ``prediction`` for LSTMs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from snncc.atomic import atomic_path
from snncc.cli.app import app
from snncc.cli.output import console, print_json
from snncc.errors import SnnccError


def load_array(path: Path) -> np.ndarray:
    """A .npy array (no pickles), or the ``inputs`` of a .npz data set."""
    if not path.is_file():
        raise SnnccError("file not found", file=str(path), field="--input")
    try:
        obj = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as ex:
        raise SnnccError(f"not a readable .npy/.npz array ({type(ex).__name__})", file=str(path), field="--input") from None
    if isinstance(obj, np.lib.npyio.NpzFile):
        with obj:
            if "inputs" not in obj.files:
                raise SnnccError(f"a .npz input needs an 'inputs' array (has {sorted(obj.files)})", file=str(path),
                                 field="inputs")
            return obj["inputs"]
    return obj


def open_runner(artefact: Path, backend: str):
    from snncc.targets.jetson.runner import ArtefactRunner, RunnerError

    try:
        return ArtefactRunner(str(artefact), backend)
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(artefact), field=ex.field) from None


@app.command("run")
def run_command(
    artefact: Path = typer.Argument(..., help="Jetson artefact directory (snncc compile --target jetson -o DIR)."),
    input: Path = typer.Option(..., "--input", "-i", help=".npy of shape (T, C) or (B, T, C) (C = the data's channels, copies are applied inside), or a data-set .npz."),
    stream: bool = typer.Option(False, "--stream", help="Feed step.onnx one time step at a time (any T, streaming)."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Write the results to this .npz (atomically)."),
    backend: str = typer.Option("auto", "--backend", help="auto (TensorRT if importable and an engine was built, else ONNX Runtime) | tensorrt | onnxruntime."),
    json_out: bool = typer.Option(False, "--json", help="Print the result summary as JSON."),
) -> None:
    """Run a Jetson artefact on inputs: the whole-sequence model, or the step model with --stream."""
    from snncc.inputs import check_batch
    from snncc.targets.jetson.runner import RunnerError

    runner = open_runner(artefact, backend)
    x = check_batch(load_array(input), spikes=runner.manifest["input"]["signal"] == "spikes", source=str(input))
    try:
        res = runner.stream(x) if stream else runner.run(x)
        used = runner.session("step" if stream else "sequence").backend
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(input), field=ex.field) from None
    if output is not None:
        with atomic_path(output) as tmp:
            with open(tmp, "wb") as fh:  # a file object: savez must not append '.npz' to the temp name
                np.savez(fh, **res)
    classes = runner.manifest["classes"]
    record = {
        "artefact": str(artefact), "backend": used, "variant": "step (streaming)" if stream else "sequence",
        "samples": int(res["prediction"].shape[0]),
        "time_steps": int(np.asarray(x).shape[-2]),
        "prediction": res["prediction"].tolist(),
        "classes": [classes[i] if 0 <= i < len(classes) else str(i) for i in res["prediction"].tolist()],
        "output": None if output is None else str(output),
    }
    if json_out:
        print_json(record)
        return
    console.print(f"{record['variant']} on {used}: {record['samples']} sample(s) x {record['time_steps']} steps")
    shown = record["classes"][:20]
    console.print("predictions: " + " ".join(shown) + (" ..." if len(record["classes"]) > 20 else ""))
    if output is not None:
        console.print(f"wrote {output}")
