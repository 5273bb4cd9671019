"""``snncc run``: Run a Jetson artefact (TensorRT or ONNX Runtime)."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("run", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def run_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Run a Jetson artefact (TensorRT or ONNX Runtime)."""
    not_built("run", "the Jetson runner")
