"""``snncc map``: Print the core map of a Loihi bundle."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("map", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def map_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Print the core map of a Loihi bundle."""
    not_built("map", "Loihi core mapping")
