"""``snncc compile``: any supported model file -> validated IR -> a target's artefact (``snncc.api.compile``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.output import print_record
from snncc.targets import available_targets


@app.command("compile")
def compile_command(
    model: Path = typer.Argument(..., help="Model file: snncc checkpoint (.pt), SpyTorch weight list (.pt, needs --params), NIR graph (.nir) or snncc IR (.snnir)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help=f"Target to compile for ({', '.join(available_targets())}). Default: the one -o's suffix names (.net -> loihi, .snnir -> ir); a Jetson directory or any other name needs --target, and a suffix that names another target is refused."),
    output: Path = typer.Option(..., "--output", "-o", help="Artefact to write (a file for ir/loihi, a directory for jetson). Written atomically."),
    params: Optional[Path] = typer.Option(None, "--params", help="The authors' parameters file (key value per line) for a SpyTorch weight list."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step in seconds, for formats that do not store one (NIR)."),
    reset: Optional[str] = typer.Option(None, "--reset", help="Reset mode for formats that do not store one (NIR): zero | subtract | zero-delayed (snnTorch's one-step-late zero reset)."),
    timing: Optional[str] = typer.Option(None, "--timing", help="Loihi: 'exact' (default) lowers the IR's delays and refractory period; 'paper' reproduces the authors' export (refDelay 1, no delays)."),
    scale: Optional[str] = typer.Option(None, "--scale", help="Loihi weight scale rule: 'global' (the paper's), 'per-layer', 'split' (per-layer, outlier weights in a second synapse format with a coarser exponent), 'fine' (each synapse its finest exponent), or 'auto' (default: the paper's unless outliers make it lossy; then the candidate with the smallest measured error)."),
    allow_reset_change: bool = typer.Option(False, "--allow-reset-change", help="Loihi: accept compiling a subtract-reset model with reset to zero (snncc check reports the cost)."),
    jetpack: Optional[str] = typer.Option(None, "--jetpack", help="Jetson: JetPack version of the board (default 4.6); selects the ONNX opset (4.6 -> 13, 5.x/6.0 -> 17, 6.1/6.2 -> 20)."),
    time_steps: Optional[int] = typer.Option(None, "--time-steps", help="Time steps per sample (default: recording length / dt). Jetson: T of the unrolled sequence model; Loihi: tSample."),
    json_out: bool = typer.Option(False, "--json", help="Print the compile report as JSON."),
) -> None:
    """Compile a trained model for a target. Every artefact is checked against the IR reference."""
    from snncc.api import compile as compile_model
    from snncc.cli.render import print_import_notes, print_notes, print_warnings

    record = compile_model(model, target=target, output=output, params=params, dt=dt, reset=reset, timing=timing,
                           scale=scale, allow_reset_change=allow_reset_change, jetpack=jetpack, time_steps=time_steps)
    if record.graph is not None:
        print_import_notes(record.graph)
    if record.target_rule != "--target":
        print_notes([f"target '{record.target}' from {record.target_rule}"])
    print_warnings(record.warnings)
    print_record(record, json_out)
