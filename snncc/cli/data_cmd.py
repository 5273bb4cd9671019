"""``snncc data``: Braille data"""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("data", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def data_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Braille data"""
    not_built("data", " synth, encode, analyse.:the Braille data tools")
