"""``snncc bench``: benchmark a Jetson artefact with the paper's protocol (and INA3221 power; ``snncc.api.bench``).

Warm-up: the whole data set six times in batches of 64; timing: six passes at batch 1, repeated
three times (median and spread). ``--power`` samples the main rail (VDD_IN) from sysfs every
50 ms during each timed repeat: min / max / average power and energy per sample.
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer
from rich.progress import BarColumn, TextColumn, TimeRemainingColumn

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import print_record, progress_bar


@app.command("bench")
@declares_paths(inputs=("artefacts", "data", "power_root"))
def bench_command(
    artefacts: List[Path] = typer.Argument(..., help="Jetson artefact directory; several are timed in one run, side by side (ratios to the first)."),
    data: Optional[Path] = typer.Option(None, "--data", help="Data set .npz (inputs, labels, meta); without it, seeded synthetic inputs (labelled so)."),
    samples: int = typer.Option(64, "--samples", help="Synthetic samples when no --data is given."),
    power: bool = typer.Option(False, "--power", help="Sample the INA3221 main rail (VDD_IN) every 50 ms during timing."),
    power_root: Path = typer.Option(Path("/"), "--power-root", help="Root of the sysfs tree to read the power monitor from."),
    rail: str = typer.Option("VDD_IN", "--rail", help="INA3221 rail to sample."),
    repeats: int = typer.Option(3, "--repeats", help="Timing repeats (median and spread are reported)."),
    warmup_passes: int = typer.Option(6, "--warmup-passes", help="Warm-up passes over the data set (batches of 64)."),
    timed_passes: int = typer.Option(6, "--timed-passes", help="Timed passes over the data set per repeat (batch 1)."),
    stream: bool = typer.Option(False, "--stream", help="Benchmark the streaming step model instead of the sequence model."),
    backend: str = typer.Option("auto", "--backend", help="auto | tensorrt | onnxruntime."),
    target: Optional[str] = typer.Option(None, "--target", "-t", help="Target whose artefacts these are (default: the one that recognises them)."),
    json_out: bool = typer.Option(False, "--json", help="Print the benchmark record as JSON."),
) -> None:
    """Per-sample latency (and power/energy) of a Jetson artefact, the paper's protocol."""
    from snncc.api import bench

    with progress_bar(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                      TimeRemainingColumn(), disable=json_out) as progress:
        record = bench(artefacts, target=target, data=data, samples=samples, power=power, power_root=power_root,
                       rail=rail, repeats=repeats, warmup_passes=warmup_passes, timed_passes=timed_passes,
                       stream=stream, backend=backend, progress=progress)
    print_record(record, json_out)
