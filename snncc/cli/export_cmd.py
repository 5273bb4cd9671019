"""``snncc export``: Export a model to another format (NIR)."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("export", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def export_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Export a model to another format (NIR)."""
    not_built("export", "NIR export")
