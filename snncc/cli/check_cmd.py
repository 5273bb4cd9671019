"""``snncc check``: measure what a target loses against the float model, on a data set.

Dispatches to ``get_target(target).check(graph, inputs, labels, options) -> record`` (a record
with ``as_dict()`` and ``render_text(console)``), so every target brings its own check.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from snncc.cli.app import app
from snncc.cli.output import console, err_console, print_json
from snncc.errors import SnnccError


def load_check_data(path: Path, graph, limit: int | None = None, labels: bool = True) -> tuple[np.ndarray, np.ndarray, dict]:
    """(inputs, labels, meta) from a Braille data set file or a plain .npz with inputs and labels
    (``labels=False``: inputs only, labels returned as None).

    Inputs with ``base_inputs`` channels are tiled ``input_copies`` times (the authors' x.tile((k,))).
    """
    meta: dict = {}
    try:
        from snncc.data.dataset import load_dataset
    except ImportError:
        load_dataset = None
    if not path.is_file():
        raise SnnccError("file does not exist", file=str(path), field="--data")
    inputs = None
    if not labels:
        try:
            with np.load(path, allow_pickle=False) as z:
                inputs = np.asarray(z["inputs"])
        except Exception as ex:  # not an npz / no 'inputs'
            raise SnnccError(f"agreement needs an .npz with an array 'inputs' (N, T, C) ({type(ex).__name__})",
                             file=str(path), field="--data") from None
        if inputs.ndim != 3:
            raise SnnccError(f"inputs must be (N, T, C), got shape {inputs.shape}", file=str(path), field="inputs")
        return _tiled(inputs[:limit] if limit is not None else inputs, graph), None, meta
    if load_dataset is not None:
        try:
            inputs, labels, meta = load_dataset(path)
        except SnnccError:
            inputs = None
    if inputs is None:
        try:
            with np.load(path, allow_pickle=False) as z:
                if "inputs" not in z or "labels" not in z:
                    raise SnnccError("a check data set needs arrays 'inputs' (N, T, C) and 'labels' (N,)",
                                     file=str(path), field="inputs" if "inputs" not in z else "labels")
                inputs, labels = z["inputs"], z["labels"]
        except SnnccError:
            raise
        except Exception as ex:  # not an npz / corrupt
            raise SnnccError(f"not a readable .npz data set ({type(ex).__name__})", file=str(path), field="--data") from None
    inputs, labels = np.asarray(inputs), np.asarray(labels)
    if inputs.ndim != 3:
        raise SnnccError(f"inputs must be (N, T, C), got shape {inputs.shape}", file=str(path), field="inputs")
    from snncc.inputs import check_dataset

    check_dataset(inputs, labels, graph, source=str(path))
    if limit is not None:
        inputs, labels = inputs[:limit], labels[:limit]
    return _tiled(inputs, graph), labels, meta


def _tiled(inputs: np.ndarray, graph) -> np.ndarray:
    """Inputs with ``base_inputs`` channels tiled ``input_copies`` times (the authors' x.tile((k,)))."""
    k = int(graph.metadata.get("input_copies", 1) or 1)
    base = graph.metadata.get("base_inputs")
    if k > 1 and base is not None and inputs.shape[2] == int(base):
        inputs = np.tile(inputs, (1, 1, k))
    return inputs


@app.command("check")
def check_command(
    model: Path = typer.Argument(..., help="Model file (as for snncc compile)."),
    target: str = typer.Option("loihi", "--target", "-t", help="Target whose losses to measure."),
    data: Optional[Path] = typer.Option(None, "--data", help="Data set: a Braille .npz (snncc data) or any .npz with inputs (N,T,C) and labels (N,); with --agreement, labels are not needed; without --data, seeded random spikes."),
    params: Optional[Path] = typer.Option(None, "--params", help="The authors' parameters file for a SpyTorch weight list."),
    dt: Optional[float] = typer.Option(None, "--dt", help="Time step in seconds, for formats that do not store one (NIR)."),
    reset: Optional[str] = typer.Option(None, "--reset", help="Reset mode for formats that do not store one (NIR)."),
    timing: Optional[str] = typer.Option(None, "--timing", help="Loihi: 'exact' (default) or 'paper' (the authors' export order)."),
    scale: Optional[str] = typer.Option(None, "--scale", help="Loihi weight scale rule: global, per-layer, split or auto (default)."),
    allow_reset_change: bool = typer.Option(False, "--allow-reset-change", help="Loihi: deploy a subtract-reset model with reset to zero."),
    stream: bool = typer.Option(False, "--stream", help="Loihi: the paper's protocol, one stream with 100 blank steps between samples."),
    limit: Optional[int] = typer.Option(None, "--limit", help="Use only the first N samples."),
    agreement: bool = typer.Option(False, "--agreement", help="Measure agreement with the float graph instead of accuracy (no labels needed; implied without --data)."),
    density: float = typer.Option(0.08, "--density", help="Without labels: spike density of the seeded random inputs (40 samples x 256 steps; --limit sets the samples)."),
    noise: float = typer.Option(0.01, "--noise", help="Without labels: multiplicative weight noise for the float graph's own sensitivity (the ceiling)."),
    json_out: bool = typer.Option(False, "--json", help="Print the record as JSON."),
) -> None:
    """Compare the float model as trained with the target, on data: accuracy, spike agreement, loss causes."""
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets import get_target

    graph = load_model(model, LoadOptions(params=params, dt=dt, reset=reset))
    given = {"timing": timing, "scale": scale, "allow_reset_change": allow_reset_change or None, "stream": stream or None}
    given = {k: v for k, v in given.items() if v is not None}   # only what the user gave (targets refuse the rest)
    if data is None or agreement:
        if target != "loihi":
            raise SnnccError("agreement without labels is measured for --target loihi", field="--target")
        from snncc.targets.loihi.agreement import measure_agreement

        x = None if data is None else load_check_data(data, graph, limit, labels=False)[0]
        record = measure_agreement(graph, {**given, "source": str(model), "data": None if data is None else str(data)},
                                   x, samples=limit or 40, density=density, noise=noise)
        if json_out:
            print_json(record.as_dict())
        else:
            record.render_text(console)
        return
    tgt = get_target(target)
    if not hasattr(tgt, "check"):
        raise SnnccError(f"target {target!r} has no check in this snncc", field="--target")
    if limit is not None and limit < 1:
        raise SnnccError("must be >= 1", field="--limit")
    inputs, labels, meta = load_check_data(data, graph, limit)
    options = {**given, "source": str(model),
               "data": str(data), "mode": "stream" if stream else "batch",
               "synthetic": bool(isinstance(meta, dict) and meta.get("synthetic"))}
    with Progress(TextColumn("checking"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=err_console, disable=json_out, transient=True) as bar:
        task = bar.add_task("check", total=len(labels))
        record = tgt.check(graph, inputs, labels, dict(options, progress=lambda n: bar.advance(task, n)))
    if json_out:
        print_json(record.as_dict() if hasattr(record, "as_dict") else record)
    elif hasattr(record, "render_text"):
        record.render_text(console)
    else:
        console.print(record)
