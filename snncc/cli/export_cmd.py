"""``snncc export``: write a model as a NIR graph for other frameworks (snnTorch, Norse, Lava, ...)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import console, print_json


@app.command("export")
@declares_paths(inputs=("model", "params"), outputs=("output",))
def export_command(
    model: Path = typer.Argument(..., help="Model file: snncc checkpoint (.pt), SpyTorch weight list (.pt, needs --params), NIR (.nir) or snncc IR (.snnir)."),
    to: str = typer.Option("nir", "--to", help="Format to write (nir)."),
    output: Path = typer.Option(..., "--output", "-o", help="File to write (written atomically)."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    nir_dt: Optional[float] = typer.Option(None, "--nir-dt", help="Step the NIR time constants are written for (default: the model's dt; snnTorch's importer has assumed 1e-4 s)."),
    json_out: bool = typer.Option(False, "--json", help="Print the export report as JSON."),
) -> None:
    """Export a spiking model to NIR. The dt convention is stored in the file's metadata and printed,
    with everything NIR cannot express (refractory periods, reset by subtraction, readout); snncc
    itself restores the identical IR from the exported file."""
    from snncc.api import export
    from snncc.cli.render import print_notes

    result = export(model, output=output, to=to, params=params, dt=dt, reset=reset, nir_dt=nir_dt)
    print_notes(result.notes)
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)
