"""``snncc emulate``: run a Loihi bundle in the bit-exact emulator.

X.npy: 0/1 spikes (bool, uint8 or float) shaped (T, C) or (B, T, C), C = the bundle's input width.
OUT.npz: output_spikes (B, T, n_out) uint8, counts (B, n_out), prediction (B,), overflow counts;
with --record all also layer{i}_spikes, layer{i}_voltage, layer{i}_current for every layer i
(the model's units only: always-on bias sources are left out).
When compile shifted the outputs (timing, current biases), an input of the model's length
tSample - output_shift gets output_shift blank steps appended, so every output step is seen.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Optional

import numpy as np
import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from snncc.atomic import write_bytes_atomic
from snncc.cli.app import app
from snncc.cli.output import console, err_console, print_json
from snncc.errors import SnnccError

CHUNK = 256


def load_spike_input(path: Path) -> np.ndarray:
    if not path.is_file():
        raise SnnccError("file does not exist", file=str(path), field="--input")
    try:
        x = np.load(path, allow_pickle=False)
    except Exception as ex:
        raise SnnccError(f"not a .npy array ({type(ex).__name__})", file=str(path), field="--input") from None
    if not isinstance(x, np.ndarray):
        raise SnnccError("expected one .npy array, got an .npz archive", file=str(path), field="--input")
    return x


@app.command("emulate")
def emulate_command(
    bundle: Path = typer.Argument(..., help="Loihi bundle (.net/.h5) written by snncc, lava-dl netx or SLAYER v1."),
    input: Path = typer.Option(..., "--input", "-i", help="Input spikes .npy: (T, C) or (B, T, C), values 0/1."),
    output: Path = typer.Option(..., "--output", "-o", help="Result .npz (written atomically)."),
    record: str = typer.Option("outputs", "--record", help="'outputs' or 'all' (every layer's spikes, voltage, current)."),
    stream: bool = typer.Option(False, "--stream", help="The paper's protocol: one continuous run, --gap blank steps between samples."),
    gap: Optional[int] = typer.Option(None, "--gap", help="Blank steps between samples in --stream mode (default 100)."),
    json_out: bool = typer.Option(False, "--json", help="Print a summary as JSON."),
) -> None:
    """Run a Loihi bundle bit-exactly (integer u, v; truncating decays; wrap and clip counted)."""
    from snncc.targets.loihi.bundle import read_bundle
    from snncc.targets.loihi.emulator import EmulationResult, check_inputs, emulate

    if record not in ("outputs", "all"):
        raise SnnccError("must be 'outputs' or 'all'", field="--record")
    from snncc.targets.loihi.validation import pad

    network = read_bundle(bundle)
    x = check_inputs(load_spike_input(input), network.input_width, source=str(input))
    shift = int(network.metadata.get("output_shift", 0) or 0)
    padded = shift if shift and x.shape[1] + shift == network.t_sample else 0
    x = pad(x, padded)
    parts: list[EmulationResult] = []
    if stream:
        result = emulate(network, x, record=record, mode="stream", gap=gap)
    else:
        with Progress(TextColumn("emulating"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      console=err_console, disable=json_out or x.shape[0] <= CHUNK, transient=True) as bar:
            task = bar.add_task("emulate", total=x.shape[0])
            for start in range(0, x.shape[0], CHUNK):
                parts.append(emulate(network, x[start:start + CHUNK], record=record, gap=gap))
                bar.advance(task, min(CHUNK, x.shape[0] - start))
        result = _merge(parts)
    arrays = {"output_spikes": result.output_spikes, "counts": result.counts, "prediction": result.prediction,
              "overflow_q_wrap": np.int64(result.overflow["q_wrap"]), "overflow_u_wrap": np.int64(result.overflow["u_wrap"]),
              "overflow_v_clip": np.int64(result.overflow["v_clip"])}
    index = network.metadata.get("hdf5_layer_index") or list(range(len(network.layers)))
    for field_name, records in (("spikes", result.spikes), ("voltage", result.voltage), ("current", result.current)):
        for i, a in records.items():   # named by HDF5 layer index (a SLAYER flatten layer has no state)
            arrays[f"layer{index[i]}_{field_name}"] = a[..., :network.layers[i].model_n]
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    write_bytes_atomic(output, buf.getvalue())
    summary = {"bundle": str(bundle), "output": str(output), "samples": int(x.shape[0]), "steps": int(x.shape[1]),
               "mode": "stream" if stream else "batch", "prediction": result.prediction,
               "overflow": result.overflow, "padded_steps": padded}
    if json_out:
        print_json(summary)
        return
    if padded:
        console.print(f"appended {padded} blank step(s) to each sample: on Loihi the outputs appear {padded} step(s) "
                      "later than in the model (see the bundle's timing record)")
    elif shift and x.shape[1] < network.t_sample:
        err_console.print(f"[yellow]warning: the bundle's outputs appear {shift} step(s) late and the input is shorter "
                          f"than tSample ({network.t_sample}); the last output steps fall outside the run[/yellow]")
    console.print(f"emulated {x.shape[0]} sample(s) x {x.shape[1]} steps ({summary['mode']} mode); overflow "
                  f"{result.overflow}; predictions {result.prediction[:20].tolist()}{' ...' if x.shape[0] > 20 else ''}")
    console.print(f"wrote {output}")


def _merge(parts):
    from snncc.targets.loihi.emulator import EmulationResult

    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    res = EmulationResult(
        output_spikes=np.concatenate([p.output_spikes for p in parts]),
        counts=np.concatenate([p.counts for p in parts]),
        prediction=np.concatenate([p.prediction for p in parts]),
        overflow={k: sum(p.overflow[k] for p in parts) for k in first.overflow},
    )
    for name in ("spikes", "voltage", "current"):
        for i in getattr(first, name):
            getattr(res, name)[i] = np.concatenate([getattr(p, name)[i] for p in parts])
    return res
