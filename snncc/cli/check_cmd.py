"""``snncc check``: measure what a target loses against the float model, on a data set (``snncc.api.check``).

The target brings its own check (``check`` capability: a record with ``as_dict()`` and
``render_text(console)``); without labels, its agreement with the float graph (``agree``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record, progress_bar
from snncc.cli.target_flags import with_target_flags


@app.command("check")
@with_target_flags("check", "agree")
@declares_paths(inputs=("model", "data", "params"))
def check_command(
    model: Path = typer.Argument(..., help="Model file (as for snncc compile)."),
    target: str = typer.Option("loihi", "--target", "-t", help="Target whose losses to measure."),
    data: Optional[Path] = typer.Option(None, "--data", help="Data set: a Braille .npz (snncc data) or any .npz with inputs (N,T,C) and labels (N,); with --agreement, labels are not needed; without --data, seeded random spikes."),
    params: Optional[Path] = typer.Option(None, "--params", help="The authors' parameters file for a SpyTorch weight list."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step in seconds, for formats that do not store one (NIR)."),
    reset: Optional[str] = typer.Option(None, "--reset", help="Reset mode for formats that do not store one (NIR)."),
    limit: Optional[int] = typer.Option(None, "--limit", help="Use only the first N samples (without --data: N random samples)."),
    agreement: bool = typer.Option(False, "--agreement", help="Measure agreement with the float graph instead of accuracy (no labels needed; implied without --data)."),
    json_out: bool = typer.Option(False, "--json", help="Print the record as JSON."),
    target_options: dict = {},
) -> None:
    """Compare the float model as trained with the target, on data: accuracy, spike agreement, loss causes.

    The target options below are declared by the targets that take them (each names its targets)."""
    from snncc.api import check

    with progress_bar(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      disable=json_out) as progress:
        record = check(model, target=target, data=data, params=params, dt=dt, reset=reset, limit=limit,
                       agreement=agreement, progress=progress, **target_options)
    print_record(record, json_out)
