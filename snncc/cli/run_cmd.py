"""``snncc run``: run a Jetson artefact (TensorRT where importable, else ONNX Runtime; ``snncc.api.run``).

``OUT.npz`` holds ``output_spikes`` (B, T, n) uint8, ``counts`` (B, n) and ``prediction`` (B,) for
SNNs (the ``snncc emulate`` contract), ``scores`` (B, n) and ``prediction`` for LSTMs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record


@app.command("run")
@declares_paths(inputs=("artefact", "input"), outputs=("output",))
def run_command(
    artefact: Path = typer.Argument(..., help="Jetson artefact directory (snncc compile --target jetson -o DIR)."),
    input: Path = typer.Option(..., "--input", "-i", "--data", help=".npy of shape (T, C) or (B, T, C) (C = the data's channels, copies are applied inside), CNN frames (B, T, C, H, W), or a data-set .npz."),
    stream: bool = typer.Option(False, "--stream", help="Feed step.onnx one time step at a time (any T, streaming)."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Write the results to this .npz (atomically)."),
    backend: str = typer.Option("auto", "--backend", help="auto (TensorRT if importable and an engine was built, else ONNX Runtime) | tensorrt | onnxruntime."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target whose artefact this is (default: the one that recognises it)."),
    json_out: bool = typer.Option(False, "--json", help="Print the result summary as JSON."),
) -> None:
    """Run a Jetson artefact on inputs: the whole-sequence model, or the step model with --stream."""
    from snncc.api import run

    print_record(run(artefact, input=input, target=target, stream=stream, output=output, backend=backend), json_out)
