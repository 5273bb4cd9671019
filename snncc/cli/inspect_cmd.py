"""``snncc inspect``: what a frontend understood of a model file, as an IR summary."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import console, print_json


@app.command("inspect")
@declares_paths(inputs=("model", "params"))
def inspect_command(
    model: Path = typer.Argument(..., help="Model file (.pt, .nir, .snnir)."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    json_out: bool = typer.Option(False, "--json", help="Print as JSON."),
) -> None:
    """Load a model, validate its IR and print it: nodes, sizes, time constants, delays, reset."""
    from snncc.api import inspect
    from snncc.cli.render import print_notes

    result = inspect(model, params=params, dt=dt, reset=reset)
    print_notes(result.notes)
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)
