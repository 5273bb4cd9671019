"""``snncc report``: Op counts, energy and delay estimate of a Loihi bundle."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("report", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def report_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Op counts, energy and delay estimate of a Loihi bundle."""
    not_built("report", "the energy report")
