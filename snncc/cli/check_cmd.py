"""``snncc check``: measure a written artefact against the float model it came from (``snncc.api.check``).

The target brings its own measurement (``check`` capability on labelled data, ``agree`` without
labels: records with ``as_dict()`` and ``render_text(console)``); ``--artefact`` names the artefact,
else the model is compiled as ``snncc compile`` would and the written result measured.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record, progress_bar
from snncc.cli.target_flags import with_target_flags


@app.command("check")
@with_target_flags("check", "agree", "lower")
@declares_paths(inputs=("model", "artefact", "data", "params"))
def check_command(
    model: Path = typer.Argument(..., help="Model file (as for snncc compile): the model the artefact came from."),
    artefact: Optional[Path] = typer.Option(None, "--artefact", "-a", help="A written artefact to measure (a Loihi bundle, a Jetson directory, ...); its target follows from it. Without it, the model is compiled as `snncc compile` would (with compile's options below), into a temporary directory, and that artefact is measured."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target to compile for and measure (default loihi; with --artefact, the artefact's)."),
    data: Optional[Path] = typer.Option(None, "--data", help="Data set: a Braille .npz (snncc data) or any .npz with inputs (N,T,C) and labels (N,); with --agreement, labels are not needed; without --data, seeded random spikes."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    limit: Optional[int] = typer.Option(None, "--limit", help="Use only the first N samples (without --data: N random samples)."),
    agreement: bool = typer.Option(False, "--agreement", help="Measure agreement with the float graph instead of accuracy (no labels needed; implied without --data)."),
    json_out: bool = typer.Option(False, "--json", help="Print the record as JSON."),
    target_options: dict = {},
) -> None:
    """Measure a written artefact (or the one compile would write) against the float model it came from: accuracy and its causes, or agreement.

    The target options below are declared by the targets that take them (each names its targets);
    compile's options apply when check compiles the model (not with --artefact)."""
    from snncc.api import check

    with progress_bar(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      disable=json_out) as progress:
        record = check(model, artefact=artefact, target=target, data=data, params=params, dt=dt, reset=reset,
                       limit=limit, agreement=agreement, progress=progress, **target_options)
    print_record(record, json_out)
