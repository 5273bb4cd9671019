"""``snncc emulate``: run a written artefact in its target's emulator, or a model file as the float graph (``snncc.api.emulate``).

X.npy (or a data set .npz's ``inputs``): (T, C) or (B, T, C) inputs, C the artefact's (or model's) input width, or in the model's own shape (the
data's channels, tiled for input copies; CNN frames (B, T, C, H, W)). OUT.npz: output_spikes (B, T, n_out) uint8,
counts (B, n_out), prediction (B,) and what the target adds; with --record all the recorded states (each target
names them: a Loihi bundle's layer{i}_spikes / _voltage / _current; the float graph's <population>_spikes /
_voltage / _current). A model file runs in the IR reference simulator (float64) with the model options.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import err_console, print_record, progress_bar


@app.command("emulate")
@declares_paths(inputs=("bundle", "input", "params"), outputs=("output",))
def emulate_command(
    bundle: Path = typer.Argument(..., metavar="ARTEFACT", help="A written artefact (a Loihi bundle .net/.h5 written by snncc, lava-dl netx or SLAYER v1; a Xylo artefact directory; any installed target's that emulates) or a model file (.pt/.nir/.snnir: the float graph, run by the IR reference)."),
    input: Path = typer.Option(..., "--input", "-i", "--data", help="Input spikes .npy: (T, C) or (B, T, C), values 0/1, or a data set .npz (its 'inputs', as check --data reads it); or in the model's shape: the data's channels (input copies tiled by snncc), CNN frames (B, T, C, H, W)."),
    output: Path = typer.Option(..., "--output", "-o", help="Result .npz (written atomically; the name must end in .npz)."),
    record: str = typer.Option("outputs", "--record", help="'outputs' or 'all' (every layer's spikes, voltage, current)."),
    stream: bool = typer.Option(False, "--stream", help="The paper's protocol: one continuous run, --gap blank steps between samples."),
    gap: Optional[int] = typer.Option(None, "--gap", help="Blank steps between samples in --stream mode (default 100)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target whose emulator runs the artefact (default: the target that recognises it)."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    json_out: bool = typer.Option(False, "--json", help="Print a summary as JSON."),
) -> None:
    """Run a written artefact bit-exactly in its target's emulator, or a model file as the float graph; save the outputs."""
    from snncc.api import emulate

    with progress_bar(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      disable=json_out) as progress:
        result = emulate(bundle, input=input, output=output, target=target, record=record, stream=stream, gap=gap,
                         params=params, dt=dt, reset=reset, progress=progress)
    if not json_out:
        for line in result.warnings():
            err_console.print(f"[yellow]warning: {line}[/yellow]")
    print_record(result, json_out)
