"""``snncc train``: train the paper's models (RSNN, FFSNN, LSTM, eLSTM) on Braille data."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import List, Optional

import typer

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import bar_columns, console, err_console, print_json, progress_bar


class ModelKind(str, Enum):
    rsnn = "rsnn"
    ffsnn = "ffsnn"
    lstm = "lstm"
    elstm = "elstm"
    fcn = "fcn"
    resnet = "resnet"
    encoder = "encoder"
    tcnn = "tcnn"
    inception = "inception"


class Order(str, Enum):
    spytorch = "spytorch"
    loihi = "loihi"


def _epoch_line(record) -> None:
    """One finished epoch on stderr: loss, train/test(/val) accuracy, seconds."""
    val = record.val_accuracy
    err_console.print(f"epoch {record.epoch}: loss {record.loss:.4f}  train {100 * record.train_accuracy:.2f} %  "
                      f"test {100 * record.test_accuracy:.2f} %" + (f"  val {100 * val:.2f} %" if val is not None else "")
                      + f"  ({record.seconds:.1f} s)")


@app.command("train")
@declares_paths(inputs=("data", "qat_from", "params"), outputs=("output",))
def train_command(
    model: ModelKind = typer.Argument(..., help="rsnn | ffsnn | lstm (frames) | elstm (events) | fcn | resnet | encoder | tcnn | inception (frames, buffered)."),
    data: Path = typer.Option(..., "--data", help="Encoded data set (.npz from snncc data encode) or a directory of published-format pickles (encoded on the fly)."),
    output: Path = typer.Option(..., "--output", "-o", help="Checkpoint to write (snncc format; snncc compile takes it directly)."),
    threshold: int = typer.Option(1, "--threshold", help="Sigma-delta threshold of the events (1, 2, 5, 10): selects the paper's preset."),
    epochs: int = typer.Option(300, "--epochs", help="Training epochs (paper: 300)."),
    subset: Optional[int] = typer.Option(None, "--subset", help="Train and test on a seeded stratified subset of N samples (smoke runs)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the initialisation, the split and the data order."),
    order: Order = typer.Option(Order.spytorch, "--order", help="SNN update order: spytorch (the authors') or loihi (one-step delays, cheapest on chip)."),
    val_fraction: float = typer.Option(0.0, "--val-fraction", help="Hold out this share of all samples (from training) to select the epoch, instead of the test set as the authors did."),
    qat_from: Optional[Path] = typer.Option(None, "--qat-from", help="Quantization-aware fine-tuning of this trained rsnn/ffsnn checkpoint (same split)."),
    qat_epochs: int = typer.Option(3, "--qat-epochs", help="Epochs of quantization-aware fine-tuning."),
    overrides: Optional[List[str]] = typer.Option(None, "--set", help="Override a preset value, KEY=VALUE (e.g. tau_mem=0.05); repeatable."),
    params: Optional[Path] = typer.Option(None, "--params", help="The authors' parameters file instead of the preset."),
    batch_size: Optional[int] = typer.Option(None, "--batch-size", help="Batch size (default: the paper's 128; the baselines: their family's, see docs/baselines.md)."),
    lr: Optional[float] = typer.Option(None, "--lr", help="Learning rate (default: the paper's Adamax 0.0015; the baselines: their family's Adam rate)."),
    device: str = typer.Option("auto", "--device", help="Where to train: auto (CUDA when available, else CPU), cpu, cuda or cuda:N. Checkpoints are always saved on the CPU."),
    threads: int = typer.Option(1, "--threads", help="Torch CPU threads (the per-step loop gains little from more; 1 avoids contention)."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bars."),
    json_out: bool = typer.Option(False, "--json", help="Print the training record as JSON."),
) -> None:
    """Train one of the paper's models with its per-threshold preset and write a checkpoint."""
    from snncc.api import train

    # the bar starts at the first batch, once the data are loaded and checked; epoch lines go to stderr
    # even when quiet
    with progress_bar(*bar_columns(remaining=True), disable=quiet or json_out, transient=False) as progress:
        result = train(model.value, data=data, output=output, threshold=threshold, epochs=epochs, subset=subset,
                       seed=seed, order=order.value, val_fraction=val_fraction, qat_from=qat_from,
                       qat_epochs=qat_epochs, overrides=overrides, params=params, batch_size=batch_size, lr=lr,
                       device=device, threads=threads, progress=progress, on_epoch=_epoch_line)
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)
