"""``snncc train``: Train the paper's models on Braille data."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("train", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def train_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Train the paper's models on Braille data."""
    not_built("train", "training")
