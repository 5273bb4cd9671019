"""``snncc map``: place a Loihi bundle (or a model, lowered first) on cores and report the core map
(``snncc.api.map``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record
from snncc.cli.target_flags import with_target_flags


@app.command("map")
@with_target_flags("map")
@declares_paths(inputs=("source",), outputs=("plot",))
def map_command(
    source: Path = typer.Argument(..., help="Loihi bundle (HDF5) or a model file (.pt/.pth/.ckpt/.snnir/.nir), lowered with the Loihi target first."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw utilisation per core as a PNG (written atomically)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target whose cores to map onto (default: the target whose artefact it is, else loihi)."),
    json_out: bool = typer.Option(False, "--json", help="Print the core map as JSON."),
    target_options: dict = {},
) -> None:
    """Place every population on Loihi 1 cores under all per-core limits; print the core map.

    The target options below apply when SOURCE is a model file, lowered first."""
    from snncc.api import map as map_cores

    print_record(map_cores(source, target=target, plot=plot, **target_options), json_out)
