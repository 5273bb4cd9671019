"""``snncc compare``: one model on every target, on the same inputs, in one table (``snncc.api.compare``)."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.output import bar_columns, print_record, progress_bar
from snncc.cli.paths import declares_paths
from snncc.cli.target_flags import with_target_flags


@app.command("compare")
@with_target_flags("lower")
@declares_paths(inputs=("model", "artefact", "data", "params"), outputs=("output", "figure"))
def compare_command(
    model: Path = typer.Argument(..., help="Model file (as for snncc compile)."),
    targets: Optional[str] = typer.Option(None, "--targets", help="Targets to compare, comma-separated (default: every installed target that compiles and checks the model)."),
    artefact: Optional[List[Path]] = typer.Option(None, "--artefact", "-a", help="A written artefact to use as its target's row instead of compiling one (repeatable; its target follows from it)."),
    data: Optional[Path] = typer.Option(None, "--data", help="Inputs: an .npz with inputs (N, T, C) and optionally labels (N,), as snncc check takes it; without it, seeded random spike trains."),
    limit: Optional[int] = typer.Option(None, "--limit", help="Use only the first N samples of --data (without it: N random samples)."),
    samples: Optional[int] = typer.Option(None, "--samples", help="Without --data: seeded random samples (default 1,000; 200 for a model of more than 200,000 neuron-steps per sample)."),
    density: float = typer.Option(0.08, "--density", help="Without --data: spike density of the seeded random inputs."),
    noise: float = typer.Option(0.01, "--noise", help="Weight noise of the float graph's ceiling row (0: no ceiling row)."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Also write the tables as Markdown (.md, atomically)."),
    figure: Optional[Path] = typer.Option(None, "--figure", help="Also draw agreement per target and energy where estimated (.png, atomically)."),
    json_out: bool = typer.Option(False, "--json", help="Print the comparison as JSON."),
    target_options: dict = {},
) -> None:
    """Compile one model for every target and measure each written artefact on the same inputs and time base: agreement, loss by cause, resources, real time, energy (ESTIMATE), NeuroBench.

    The target options below are compile's; each applies to the targets that declare it."""
    from snncc.api import compare

    with progress_bar(*bar_columns(), disable=json_out) as progress:
        record = compare(model, targets=targets, artefacts=artefact or (), data=data, limit=limit, samples=samples,
                         density=density, noise=noise, params=params, dt=dt, reset=reset, output=output,
                         figure=figure, progress=progress, **target_options)
    print_record(record, json_out)
