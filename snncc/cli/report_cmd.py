"""``snncc report BUNDLE --energy``: ESTIMATE of energy and delay per sample on Loihi 1."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from snncc.cli.app import app
from snncc.cli.output import console, err_console, print_json
from snncc.errors import SnnccError


def _fit_inputs(x: np.ndarray, network, source: str) -> tuple[np.ndarray, str]:
    """(B, T, C) data -> the bundle's input width (input copies tiled) and tSample steps."""
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3:
        raise SnnccError(f"inputs must be (T, C) or (B, T, C), got shape {x.shape}", file=source, field="inputs")
    width = network.input_width
    notes = []
    if x.shape[2] != width:
        if width % x.shape[2]:
            raise SnnccError(f"inputs have {x.shape[2]} channels; the bundle's input layer has {width}",
                             file=source, field="inputs")
        k = width // x.shape[2]
        x = np.tile(x, (1, 1, k))
        notes.append(f"channels tiled x{k} (input copies)")
    t = network.t_sample
    if x.shape[1] < t:
        x = np.concatenate([x, np.zeros((x.shape[0], t - x.shape[1], x.shape[2]), x.dtype)], axis=1)
        notes.append(f"padded with zeros to tSample {t}")
    elif x.shape[1] > t:
        x = x[:, :t]
        notes.append(f"cut to tSample {t}")
    return x, "; ".join(notes)


@app.command("report")
def report_command(
    bundle: Path = typer.Argument(..., help="Loihi bundle (HDF5) to estimate."),
    energy: bool = typer.Option(False, "--energy", help="Estimate energy and delay per sample (Davies 2018 Table 2)."),
    data: Optional[Path] = typer.Option(None, "--data", help="Data set (.npz with inputs, labels, meta) to emulate."),
    input_file: Optional[Path] = typer.Option(None, "--input", help="Spike input .npy, (T, C) or (B, T, C)."),
    limit: Optional[int] = typer.Option(None, "--limit", help="Use the first N samples only."),
    samples: Optional[int] = typer.Option(None, "--samples", help="Without data: how many random input samples (default 8)."),
    rate: Optional[float] = typer.Option(None, "--rate", help="Without data: spike probability per input channel and step (default 0.05)."),
    seed: Optional[int] = typer.Option(None, "--seed", help="Without data: random seed (default 0)."),
    json_out: bool = typer.Option(False, "--json", help="Print the report as JSON."),
) -> None:
    """ESTIMATE (not a measurement) of energy and delay per sample, beside the paper's measurement."""
    from rich.progress import Progress

    from snncc.cli.map_cmd import load_network
    from snncc.targets.loihi.energy import emulate_and_estimate
    from snncc.targets.loihi.partition import map_network

    if not energy:
        raise SnnccError("nothing to report: pass --energy", field="snncc report")
    if data is not None and input_file is not None:
        raise SnnccError("give --data or --input, not both", field="--input")
    if limit is not None and limit < 1:
        raise SnnccError("must be >= 1", field="--limit")
    if data is not None or input_file is not None:
        for flag, value in (("--samples", samples), ("--rate", rate), ("--seed", seed)):
            if value is not None:
                raise SnnccError("applies only to random inputs, not with --data or --input", field=flag)
    samples, rate, seed = 8 if samples is None else samples, 0.05 if rate is None else rate, 0 if seed is None else seed
    network = load_network(bundle)
    if data is not None:
        from snncc.data.dataset import load_dataset

        x, _, _ = load_dataset(data)
        source, note = str(data), f"data set {data.name}"
    elif input_file is not None:
        if not input_file.is_file():
            raise SnnccError("file does not exist", file=str(input_file))
        try:
            x = np.load(input_file, allow_pickle=False)
        except (OSError, ValueError) as ex:
            raise SnnccError(f"not a readable .npy array ({type(ex).__name__})", file=str(input_file))
        source, note = str(input_file), f"input file {input_file.name}"
    else:
        if not 0.0 <= rate <= 1.0 or samples < 1:
            raise SnnccError("need 0 <= --rate <= 1 and --samples >= 1", field="--rate/--samples")
        from snncc.limits import check_memory

        check_memory(8 * samples * network.t_sample * network.input_width,
                     f"{samples:,} random samples of {network.t_sample} steps x {network.input_width} channels",
                     field="--samples")
        rng = np.random.default_rng(seed)
        x = (rng.random((samples, network.t_sample, network.input_width)) < rate).astype(np.uint8)
        source = "<random>"
        note = (f"SYNTHETIC: {samples} seeded random sparse input samples (rate {rate}, seed {seed}); "
                "no data given")
    x = np.asarray(x)
    if limit is not None:
        x = x[:limit]
    x, fit = _fit_inputs(x, network, source)
    if fit:
        note = f"{note} ({fit})"
    try:
        cmap = map_network(network)
    except SnnccError as err:
        raise err.with_file(str(bundle))
    with Progress(console=err_console, transient=True, disable=json_out) as bar:
        task = bar.add_task("emulating", total=x.shape[0])
        est = emulate_and_estimate(cmap.network, cmap, x, note, progress=lambda done: bar.update(task, completed=done))
    if cmap.transforms:
        est.assumptions.append("the network was emulated with the fan-in relays the map inserted (see snncc map)")
    if json_out:
        print_json({"bundle": str(bundle), "estimate": est.to_dict(), "core_map": {
            "n_cores": cmap.n_cores, "n_chips": cmap.n_chips, "lower_bound": cmap.lower_bound}})
        return
    est.render_text(console)
