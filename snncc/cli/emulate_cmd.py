"""``snncc emulate``: Run a Loihi bundle in the bit-exact emulator."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("emulate", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def emulate_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Run a Loihi bundle in the bit-exact emulator."""
    not_built("emulate", "the Loihi emulator")
