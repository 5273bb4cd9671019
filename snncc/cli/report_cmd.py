"""``snncc report BUNDLE --energy``: ESTIMATE of energy and delay per sample on Loihi 1 (``snncc.api.report``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.progress import BarColumn, TaskProgressColumn, TextColumn, TimeRemainingColumn

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record, progress_bar


@app.command("report")
@declares_paths(inputs=("bundle", "data", "input_file", "params"))
def report_command(
    bundle: Path = typer.Argument(..., metavar="ARTEFACT", help="A written artefact (or, without --energy, a model file, compiled first as snncc compile would)."),
    energy: bool = typer.Option(False, "--energy", help="Estimate energy and delay per sample where the target has a published cost model (Loihi: Davies 2018 Table 2); without it, the resource report (snncc map's)."),
    data: Optional[Path] = typer.Option(None, "--data", help="Data set (.npz with inputs, labels, meta) to emulate."),
    input_file: Optional[Path] = typer.Option(None, "--input", help="Spike input .npy, (T, C) or (B, T, C)."),
    limit: Optional[int] = typer.Option(None, "--limit", help="Use the first N samples only."),
    samples: Optional[int] = typer.Option(None, "--samples", help="Without data: how many random input samples (default 8)."),
    rate: Optional[float] = typer.Option(None, "--rate", help="Without data: spike probability per input channel and step (default 0.05)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Without data: random seed (default 0)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target (default: the artefact's; for a model file the default target, as compile)."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    json_out: bool = typer.Option(False, "--json", help="Print the report as JSON."),
) -> None:
    """What an artefact uses of its hardware; with --energy, the ESTIMATE (not a measurement) of energy and delay per sample."""
    from snncc.api import report

    with progress_bar(TextColumn("{task.description}"), BarColumn(), TaskProgressColumn(), TimeRemainingColumn(),
                      disable=json_out) as progress:
        record = report(bundle, target=target, energy=energy, data=data, input=input_file, limit=limit,
                        samples=samples, rate=rate, seed=seed, params=params, dt=dt, reset=reset, progress=progress)
    print_record(record, json_out)
