"""``snncc map``: place a written artefact (or a model file, compiled first) on its target's hardware (``snncc.api.map``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record
from snncc.cli.target_flags import with_target_flags


@app.command("map")
@with_target_flags("map", "lower")
@declares_paths(inputs=("source", "params"), outputs=("plot",))
def map_command(
    source: Path = typer.Argument(..., help="A written artefact (Loihi bundle, Xylo directory, ...) or a model file (.pt/.pth/.ckpt/.snnir/.nir), compiled first exactly as snncc compile would (with the model and compile options below)."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw the map as a PNG (written atomically; the name must end in .png)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target to map onto (default: the artefact's; for a model file the default target, as compile)."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    json_out: bool = typer.Option(False, "--json", help="Print the core map as JSON."),
    target_options: dict = {},
) -> None:
    """Place a model on its target's hardware (Loihi: cores under every per-core limit; Xylo: neurons, synapses and fan-out against the chip's limits) and print the map.

    The model and target options below apply when SOURCE is a model file, compiled first."""
    from snncc.api import map as map_cores

    print_record(map_cores(source, target=target, plot=plot, params=params, dt=dt, reset=reset, **target_options),
                 json_out)
