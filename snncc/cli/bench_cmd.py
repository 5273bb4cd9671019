"""``snncc bench``: benchmark a Jetson artefact with the paper's protocol (and INA3221 power).

Warm-up: the whole data set six times in batches of 64; timing: six passes at batch 1, repeated
three times (median and spread). ``--power`` samples the main rail (VDD_IN) from sysfs every
50 ms during each timed repeat: min / max / average power and energy per sample.
"""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import numpy as np
import typer
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from snncc.cli.app import app
from snncc.cli.output import console, err_console, print_json
from snncc.cli.run_cmd import open_runner
from snncc.errors import SnnccError


def synthetic_inputs(manifest: dict, samples: int, seed: int) -> np.ndarray:
    """Seeded random inputs of the artefact's shape (events at 10 %, or N(0, 1) frames)."""
    rng = np.random.default_rng(seed)
    shape = (samples, manifest["time_steps"], manifest["input"]["channels"])
    if manifest["input"]["signal"] == "spikes":
        return (rng.random(shape) < 0.1).astype(np.float32)
    return rng.standard_normal(shape).astype(np.float32)


@app.command("bench")
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
    json_out: bool = typer.Option(False, "--json", help="Print the benchmark record as JSON."),
) -> None:
    """Per-sample latency (and power/energy) of a Jetson artefact, the paper's protocol."""
    from snncc.targets.jetson.benchmark import run_protocol
    from snncc.targets.jetson.power import PowerSampler
    from snncc.targets.jetson.runner import RunnerError

    for name, value in (("--repeats", repeats), ("--warmup-passes", warmup_passes + 1), ("--timed-passes", timed_passes), ("--samples", samples)):
        if value < 1:
            raise SnnccError("must be >= 1 (warm-up passes >= 0)", field=name)
    if len(artefacts) > 1:
        if power:
            raise SnnccError("power is sampled for one artefact at a time", field="--power")
        return _bench_many(artefacts, data, samples, backend, repeats, warmup_passes, timed_passes, stream, json_out)
    artefact = artefacts[0]
    runner = open_runner(artefact, backend)
    labels = None
    if data is not None:
        from snncc.data.dataset import load_dataset

        inputs, labels, meta = load_dataset(data)
        label = f"{data} ({'synthetic' if meta.get('synthetic') else 'recorded'} data, {len(labels)} samples)"
    else:
        inputs = synthetic_inputs(runner.manifest, samples, seed=0)
        label = f"synthetic random inputs ({samples} samples, seed 0): latency only, no accuracy"
    sampler = PowerSampler(root=str(power_root), rail_name=rail) if power else None
    n = len(inputs)
    total = warmup_passes * n + timed_passes * n * repeats
    try:
        with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                      TimeRemainingColumn(), console=err_console, transient=True, disable=json_out) as bar:
            task = bar.add_task("benchmark", total=total)
            record = run_protocol(runner, inputs, labels, data_label=label, warmup_passes=warmup_passes,
                                  timed_passes=timed_passes, repeats=repeats, stream=stream, sampler=sampler,
                                  progress=lambda phase, k: bar.update(task, advance=k, description=phase))
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(data or artefact), field=ex.field) from None
    if not power:
        record.notes.append("power not sampled (use --power on a Jetson)")
    if json_out:
        print_json(record.as_dict())
        return
    console.print(f"[bold]snncc bench[/bold] {artefact} ({record.variant}, {record.backend})  data: {record.data}")
    console.print(f"per-sample latency: median {record.median_ms:.3f} ms, spread {record.spread_ms:.3f} ms over "
                  f"{repeats} repeats ({', '.join(f'{v:.3f}' for v in record.per_sample_ms)} ms)")
    if record.accuracy is not None:
        console.print(f"accuracy: {record.accuracy:.2%}")
    if record.power_summary:
        p = record.power_summary
        console.print(f"power ({p['rail']}): min {p['min_mw']:.0f} mW, max {p['max_mw']:.0f} mW, avg {p['avg_mw']:.0f} mW; "
                      f"energy per sample {p['energy_per_sample_uj']:.0f} uJ (spread {p['energy_spread_uj']:.0f})")
    for note in record.notes:
        console.print(f"note: {note}")


def _bench_many(artefacts, data, samples, backend, repeats, warmup_passes, timed_passes, stream, json_out) -> None:
    """Several artefacts with the same protocol; each takes --data when its channels fit, else seeded inputs."""
    from snncc.targets.jetson.benchmark import compare_protocol
    from snncc.targets.jetson.runner import RunnerError

    loaded = None
    if data is not None:
        from snncc.data.dataset import load_dataset

        loaded = load_dataset(data)
    entries = []
    for artefact in artefacts:
        runner = open_runner(artefact, backend)
        channels = runner.manifest["input"]["channels"]
        if loaded is not None and loaded[0].shape[2] == channels and (
                runner.manifest["time_axis"] == "dynamic" or loaded[0].shape[1] == runner.manifest["time_steps"]):
            inputs, labels = loaded[0], loaded[1]
            label = f"{data} ({'synthetic' if loaded[2].get('synthetic') else 'recorded'} data, {len(labels)} samples)"
        else:
            inputs, labels = synthetic_inputs(runner.manifest, samples, seed=0), None
            label = f"synthetic random inputs ({samples} samples, seed 0): latency only"
        entries.append((runner, inputs, labels, label))
    try:
        record = compare_protocol(entries, warmup_passes=warmup_passes, timed_passes=timed_passes, repeats=repeats,
                                  stream=stream)
    except RunnerError as ex:
        raise SnnccError(ex.rule, file=str(data or artefacts[0]), field=ex.field) from None
    if json_out:
        print_json(record.as_dict())
        return
    console.print(record.table(), markup=False, soft_wrap=True)
    console.print("note: batch-1 latency, the paper's protocol; ratios are to the first artefact; power not sampled",
                  soft_wrap=True)
