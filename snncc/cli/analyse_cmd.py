"""``snncc analyse ttc``: time to classification of trained models, JSON + one accuracy-vs-signal figure."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import console, print_json

analyse_app = typer.Typer(help="Analyse trained models (time to classification).", no_args_is_help=True)
app.add_typer(analyse_app, name="analyse")


@analyse_app.command("ttc")
@declares_paths(inputs=("models", "data"), outputs=("output", "figure"))
def ttc_command(
    models: List[Path] = typer.Argument(..., help="snncc checkpoints (any kind: rsnn, ffsnn, lstm, elstm, fcn, resnet, encoder, tcnn, inception)."),
    data: List[Path] = typer.Option(..., "--data", help="Data set(s): each model takes the first of its encoding (events or frames); repeatable."),
    split: str = typer.Option("test", "--split", help="test (each checkpoint's own test samples) or all."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Write the records as JSON (atomically)."),
    figure: Optional[Path] = typer.Option(None, "--figure", help="Accuracy vs signal fraction of all models in one figure (.png, .pdf or .svg)."),
    json_out: bool = typer.Option(False, "--json", help="Print the records as JSON."),
) -> None:
    """Per sample and averaged, the earliest share of the signal after which the prediction is right and stays right."""
    from snncc.api import analyse_ttc

    result = analyse_ttc(models, data=data, split=split, output=output, figure=figure)
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)
