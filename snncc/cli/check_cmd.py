"""``snncc check``: Measure what a target loses against the float model."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("check", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def check_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Measure what a target loses against the float model."""
    not_built("check", "the quantization-loss check")
