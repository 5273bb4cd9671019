"""``snncc emulate``: run a Loihi bundle in the bit-exact emulator (``snncc.api.emulate``).

X.npy: 0/1 spikes (bool, uint8 or float) shaped (T, C) or (B, T, C), C = the bundle's input width, or in
the model's own shape (the data's channels, tiled for the bundle's input copies; CNN frames (B, T, C, H, W)).
OUT.npz: output_spikes (B, T, n_out) uint8, counts (B, n_out), prediction (B,), overflow counts;
with --record all also layer{i}_spikes, layer{i}_voltage, layer{i}_current for every layer i
(the model's units only: always-on bias sources are left out).
When compile shifted the outputs (timing, current biases), an input of the model's length
tSample - output_shift gets output_shift blank steps appended, so every output step is seen.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import err_console, print_record, progress_bar


@app.command("emulate")
@declares_paths(inputs=("bundle", "input"), outputs=("output",))
def emulate_command(
    bundle: Path = typer.Argument(..., help="Loihi bundle (.net/.h5) written by snncc, lava-dl netx or SLAYER v1."),
    input: Path = typer.Option(..., "--input", "-i", help="Input spikes .npy: (T, C) or (B, T, C), values 0/1; or in the model's shape: the data's channels (input copies tiled by snncc), CNN frames (B, T, C, H, W)."),
    output: Path = typer.Option(..., "--output", "-o", help="Result .npz (written atomically)."),
    record: str = typer.Option("outputs", "--record", help="'outputs' or 'all' (every layer's spikes, voltage, current)."),
    stream: bool = typer.Option(False, "--stream", help="The paper's protocol: one continuous run, --gap blank steps between samples."),
    gap: Optional[int] = typer.Option(None, "--gap", help="Blank steps between samples in --stream mode (default 100)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target whose emulator runs the bundle (default: the target whose artefact it is, else loihi)."),
    json_out: bool = typer.Option(False, "--json", help="Print a summary as JSON."),
) -> None:
    """Run a Loihi bundle bit-exactly (integer u, v; truncating decays; wrap and clip counted)."""
    from snncc.api import emulate

    with progress_bar(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      disable=json_out) as progress:
        result = emulate(bundle, input=input, output=output, target=target, record=record, stream=stream, gap=gap,
                         progress=progress)
    if not json_out:
        for line in result.warnings():
            err_console.print(f"[yellow]warning: {line}[/yellow]")
    print_record(result, json_out)
