"""``snncc analyse ttc``: time to classification of trained models, JSON + one accuracy-vs-signal figure."""

from __future__ import annotations

import json
from pathlib import Path
from typing import List, Optional

import typer

from snncc.cli.app import app
from snncc.cli.output import console, print_json
from snncc.errors import SnnccError

analyse_app = typer.Typer(help="Analyse trained models (time to classification).", no_args_is_help=True)
app.add_typer(analyse_app, name="analyse")


@analyse_app.command("ttc")
def ttc_command(
    models: List[Path] = typer.Argument(..., help="snncc checkpoints (any kind: rsnn, ffsnn, lstm, elstm, fcn, resnet, encoder, tcnn, inception)."),
    data: List[Path] = typer.Option(..., "--data", help="Data set(s): each model takes the first of its encoding (events or frames); repeatable."),
    split: str = typer.Option("test", "--split", help="test (each checkpoint's own test samples) or all."),
    output: Optional[Path] = typer.Option(None, "--output", "-o", help="Write the records as JSON (atomically)."),
    figure: Optional[Path] = typer.Option(None, "--figure", help="Accuracy vs signal fraction of all models in one figure (.png, .pdf or .svg)."),
    json_out: bool = typer.Option(False, "--json", help="Print the records as JSON."),
) -> None:
    """Per sample and averaged, the earliest share of the signal after which the prediction is right and stays right."""
    from snncc.atomic import write_text_atomic
    from snncc.training.ttc import FIGURE_FORMATS, plot_accuracy_vs_fraction, ttc_of_checkpoints, ttc_table

    if figure is not None and figure.suffix.lstrip(".").lower() not in FIGURE_FORMATS:
        raise SnnccError(f"the figure must be one of {', '.join(FIGURE_FORMATS)}", file=str(figure), field="--figure")
    records = ttc_of_checkpoints([str(m) for m in models], [str(d) for d in data], split)
    payload = {"rule": "TTC = the smallest k/T after which the prediction is correct at every later prefix; "
                       "None when wrong on the whole signal; means over the samples with a TTC",
               "models": [r.as_dict() for r in records]}
    if output is not None:
        write_text_atomic(output, json.dumps(payload, indent=2) + "\n")
    if figure is not None:
        synthetic = any("SYNTHETIC" in r.data for r in records)
        plot_accuracy_vs_fraction(records, figure, title="accuracy vs share of the signal seen"
                                  + (" (SYNTHETIC data)" if synthetic else ""))
    if json_out:
        print_json(payload)
        return
    console.print(ttc_table(records), markup=False, soft_wrap=True)
    for r in records:
        console.print(f"{r.model}: {r.method}; {'; '.join(r.notes)}; data {r.data}", markup=False, soft_wrap=True)
    for path in (output, figure):
        if path is not None:
            console.print(f"wrote {path}")
