"""``snncc bench``: Benchmark a Jetson artefact with the paper's protocol."""

from __future__ import annotations

from typing import List

import typer

from snncc.cli.app import app
from snncc.cli.pending import not_built


@app.command("bench", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def bench_command(args: List[str] = typer.Argument(None, help="Arguments (not built yet).")) -> None:
    """Benchmark a Jetson artefact with the paper's protocol."""
    not_built("bench", "the Jetson benchmark")
