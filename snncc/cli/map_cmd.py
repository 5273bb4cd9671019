"""``snncc map``: place a Loihi bundle (or a model, lowered first) on cores and report the core map
(``snncc.api.map``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.output import print_record


@app.command("map")
def map_command(
    source: Path = typer.Argument(..., help="Loihi bundle (HDF5) or a model file (.pt/.pth/.ckpt/.snnir/.nir), lowered with the Loihi target first."),
    json_out: bool = typer.Option(False, "--json", help="Print the core map as JSON."),
    plot: Optional[Path] = typer.Option(None, "--plot", help="Also draw utilisation per core as a PNG (written atomically)."),
    timing: Optional[str] = typer.Option(None, "--timing", help="For a model file: Loihi timing 'exact' (default) or 'paper' (the authors' export)."),
    scale: Optional[str] = typer.Option(None, "--scale", help="For a model file: Loihi weight scale rule (auto (default) | global | per-layer | split)."),
    target: str = typer.Option("loihi", "--target", "-t", help="Target whose cores to map onto."),
) -> None:
    """Place every population on Loihi 1 cores under all per-core limits; print the core map."""
    from snncc.api import map as map_cores

    print_record(map_cores(source, target=target, plot=plot, timing=timing, scale=scale), json_out)
