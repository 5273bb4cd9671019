"""``snncc compile``: any supported model file -> validated IR -> a target's artefact (``snncc.api.compile``)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.model_options import dt_option, params_option, reset_option
from snncc.cli.paths import declares_paths
from snncc.cli.output import bar_columns, print_record, progress_bar
from snncc.cli.target_flags import with_target_flags
from snncc.targets import available_targets, output_suffixes


@app.command("compile")
@with_target_flags("lower", "finetune")
@declares_paths(inputs=("model", "params"), outputs=("output",))
def compile_command(
    model: Path = typer.Argument(..., help="Model file: snncc checkpoint (.pt), SpyTorch weight list (.pt, needs --params), NIR graph (.nir) or snncc IR (.snnir)."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help=f"Target to compile for ({', '.join(available_targets())}). Default: the one -o's suffix names ({', '.join(f'{s} -> {t}' for t, s in output_suffixes().items())}); any other name needs --target, and a suffix that names another target is refused."),
    output: Path = typer.Option(..., "--output", "-o", help="Artefact to write (a file or a directory, as the target writes it). Written atomically."),
    params: Optional[Path] = params_option(),
    dt: Optional[float] = dt_option(),
    reset: Optional[str] = reset_option(),
    json_out: bool = typer.Option(False, "--json", help="Print the compile report as JSON."),
    target_options: dict = {},
) -> None:
    """Compile a trained model for a target. Every artefact is checked against the IR reference.

    The target options below are declared by the targets that take them (each names its targets)."""
    from snncc.api import compile as compile_model
    from snncc.cli.render import print_import_notes, print_notes, print_warnings

    with progress_bar(*bar_columns(), disable=json_out) as progress:
        record = compile_model(model, target=target, output=output, params=params, dt=dt, reset=reset,
                               progress=progress, **target_options)
    if record.graph is not None:
        print_import_notes(record.graph)
    if record.target_rule != "--target":
        print_notes([f"target '{record.target}' from {record.target_rule}"])
    print_warnings(record.warnings)
    print_record(record, json_out)
