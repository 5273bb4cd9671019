"""The training loop of the paper (Adamax, batch 128, epoch selection) for the zoo's models.

Seeded and reproducible: the caller seeds the initialisation (``torch.manual_seed``); the data
order of epoch e is a permutation drawn from ``torch.Generator().manual_seed(seed + e)``. The
weights kept are those of the best epoch on the *test* set when no validation split is given --
what the authors did (it flatters the test accuracy) -- or on the validation split otherwise.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import torch
from torch import nn

from snncc.models import LSTMClassifier, SpikingClassifier
from snncc.progress import Progress as VerbProgress
from snncc.training.loss import LossParts, lstm_loss, mse_sigmoid_loss, snn_loss, spike_count_prediction

Forward = Callable[[nn.Module, torch.Tensor], object]

SELECTION_NOTES = {
    "test": "weights of the best TEST epoch kept, as the authors did: the test accuracy is optimistic "
            "(use --val-fraction to select on a validation split)",
    "val": "weights of the best VALIDATION epoch kept; the test set was not used for selection",
    "last": "weights of the last epoch kept",
}


@dataclass
class TrainSettings:
    epochs: int = 300
    batch_size: int = 128
    lr: float = 0.0015
    betas: tuple[float, float] = (0.9, 0.995)
    seed: int = 0
    reg_spikes: float = 0.0
    reg_neurons: float = 0.0
    optimiser: str = "adamax"              # "adamax" (the paper's SNNs/LSTMs) | "adam" (the time-series family)
    loss: str = "cross_entropy"            # | "mse_sigmoid" (Time-CNN: MSE of sigmoid outputs vs one-hot)
    plateau: tuple | None = None           # ReduceLROnPlateau on the training loss: (factor, patience, min_lr)


@dataclass
class EpochRecord:
    epoch: int                 # 1-based
    loss: float
    nll: float
    train_accuracy: float      # on the batches as trained (running)
    test_accuracy: float
    val_accuracy: float | None
    hidden_spikes_per_sample: float | None
    seconds: float


@dataclass
class History:
    selected_on: str           # "test" | "val" | "last"
    note: str
    epochs: list[EpochRecord] = field(default_factory=list)
    best_epoch: int = 0
    best_test_accuracy: float = float("nan")
    best_val_accuracy: float | None = None

    def collapse_note(self, drop: float = 0.2) -> str | None:
        """A note when the last epoch's test accuracy fell more than ``drop`` (0..1) below the kept
        epoch's: the checkpoint holds the kept epoch, but the training itself did not stay there."""
        if not self.epochs or self.best_epoch < 1 or self.epochs[-1].epoch == self.best_epoch:
            return None
        best, last = self.epochs[self.best_epoch - 1], self.epochs[-1]
        if not best.test_accuracy - last.test_accuracy > drop:
            return None
        note = (f"training fell back after epoch {best.epoch}: test accuracy {100 * best.test_accuracy:.1f} % there, "
                f"{100 * last.test_accuracy:.1f} % at the last epoch ({last.epoch})")
        if best.hidden_spikes_per_sample is not None and last.hidden_spikes_per_sample is not None:
            note += (f"; hidden spikes per sample {best.hidden_spikes_per_sample:,.0f} -> "
                     f"{last.hidden_spikes_per_sample:,.0f}")
        return note + f"; the checkpoint holds epoch {best.epoch}"

    def summary(self) -> dict:
        last = self.epochs[-1] if self.epochs else None
        return {"epochs_run": len(self.epochs), "selected_on": self.selected_on, "note": self.note,
                "best_epoch": self.best_epoch, "test_accuracy": self.best_test_accuracy,
                "val_accuracy": self.best_val_accuracy,
                "last_epoch_test_accuracy": last.test_accuracy if last else None,
                "seconds": sum(e.seconds for e in self.epochs)}


def plain_forward(model: nn.Module, x: torch.Tensor):
    return model(x)


def is_spiking(model: nn.Module) -> bool:
    return isinstance(model, SpikingClassifier)


def batch_loss(model: nn.Module, outputs, labels: torch.Tensor, settings: TrainSettings) -> LossParts:
    if is_spiking(model):
        out_spikes, hidden = outputs
        return snn_loss(out_spikes, hidden, labels, settings.reg_spikes, settings.reg_neurons)
    if settings.loss == "mse_sigmoid":
        return mse_sigmoid_loss(outputs, labels)
    return lstm_loss(outputs, labels)


def predictions_of(model: nn.Module, outputs) -> torch.Tensor:
    if is_spiking(model):
        return spike_count_prediction(outputs[0])
    return torch.argmax(outputs, dim=1)


def as_input(model: nn.Module, x: torch.Tensor) -> torch.Tensor:
    """``x`` in the model's dtype, on the model's device (data sets stay on the CPU)."""
    first = next(model.parameters())
    return x.to(device=first.device, dtype=first.dtype, non_blocking=True)


@torch.no_grad()
def predict(model: nn.Module, inputs: torch.Tensor, batch_size: int = 256, forward: Forward = plain_forward) -> np.ndarray:
    """Class predictions for (N, T, C) inputs, in batches, without gradients."""
    was_training = model.training
    model.eval()
    out = []
    for start in range(0, inputs.shape[0], batch_size):
        xb = as_input(model, inputs[start:start + batch_size])
        out.append(predictions_of(model, forward(model, xb)))
    model.train(was_training)
    return torch.cat(out).cpu().numpy() if out else np.zeros(0, dtype=np.int64)


def accuracy(model: nn.Module, inputs: torch.Tensor, labels: torch.Tensor, batch_size: int = 256,
             forward: Forward = plain_forward) -> float:
    """Share of correctly classified samples (0..1)."""
    if inputs.shape[0] == 0:
        return float("nan")
    pred = predict(model, inputs, batch_size, forward)
    return float(np.mean(pred == labels.cpu().numpy()))


def make_optimiser(model: nn.Module, settings: TrainSettings) -> torch.optim.Optimizer:
    trainable = [p for p in model.parameters() if p.requires_grad]
    if settings.optimiser == "adam":
        return torch.optim.Adam(trainable, lr=settings.lr, betas=tuple(settings.betas))
    return torch.optim.Adamax(trainable, lr=settings.lr, betas=tuple(settings.betas))


def make_scheduler(optimiser: torch.optim.Optimizer, settings: TrainSettings):
    """ReduceLROnPlateau on the epoch's training loss (the time-series family's schedule), or None."""
    if settings.plateau is None:
        return None
    factor, patience, min_lr = settings.plateau
    return torch.optim.lr_scheduler.ReduceLROnPlateau(optimiser, mode="min", factor=factor, patience=int(patience),
                                                      min_lr=min_lr)


def train_model(
    model: nn.Module,
    train: tuple[torch.Tensor, torch.Tensor],
    test: tuple[torch.Tensor, torch.Tensor],
    settings: TrainSettings,
    val: tuple[torch.Tensor, torch.Tensor] | None = None,
    forward: Forward = plain_forward,
    progress: VerbProgress | None = None,
    select: str | None = None,
    keep_start: bool = False,
    device=None,
    on_epoch: Callable[[EpochRecord], None] | None = None,
) -> History:
    """Train ``model`` in place; at the end it holds the selected epoch's weights (back on the CPU).

    ``select`` is "test" (default without ``val``), "val" (default with it) or "last".
    ``keep_start``: the starting weights compete as epoch 0 (fine-tuning never returns worse
    weights, on the selection metric, than it was given). ``progress(done, total, "epoch e/E")``:
    called after each batch, ``done`` counting batches over all epochs (None: silent).
    ``device``: a ``torch.device`` to train on (default: where the model is); the data stay on the
    CPU and each batch is moved to it. ``on_epoch(record)``: called after each epoch (e.g. a
    hyper-parameter search reporting intermediate values); an exception it raises stops training.
    """
    if device is not None:
        model.to(device)
    x_train, y_train = train
    if select is None:
        select = "val" if val is not None and val[0].shape[0] > 0 else "test"
    history = History(selected_on=select, note=SELECTION_NOTES[select])
    optimiser = make_optimiser(model, settings)
    scheduler = make_scheduler(optimiser, settings)
    try:
        _epochs(model, x_train, y_train, test, val, settings, forward, progress, optimiser, history, select,
                keep_start, scheduler, on_epoch)
    finally:
        model.to("cpu")
    return history


def _epochs(model, x_train, y_train, test, val, settings, forward, progress, optimiser, history, select,
            keep_start=False, scheduler=None, on_epoch=None):
    n = x_train.shape[0]
    total_batches, batches_done = settings.epochs * -(-n // settings.batch_size), 0
    best_metric, best_state = -1.0, None
    if keep_start and select != "last":
        test_acc = accuracy(model, test[0], test[1], forward=forward)
        val_acc = accuracy(model, val[0], val[1], forward=forward) if val is not None and val[0].shape[0] else None
        best_metric = test_acc if select == "test" else val_acc
        best_state = copy.deepcopy(model.state_dict())
        history.best_epoch, history.best_test_accuracy, history.best_val_accuracy = 0, test_acc, val_acc
    for epoch in range(1, settings.epochs + 1):
        started = time.perf_counter()
        model.train()
        order = torch.randperm(n, generator=torch.Generator().manual_seed(settings.seed * 100003 + epoch))
        total_loss = total_nll = 0.0
        correct, hidden_spikes = 0, 0.0
        for start in range(0, n, settings.batch_size):
            idx = order[start:start + settings.batch_size]
            xb = as_input(model, x_train[idx])
            yb = y_train[idx].to(xb.device, non_blocking=True)
            outputs = forward(model, xb)
            parts = batch_loss(model, outputs, yb, settings)
            optimiser.zero_grad(set_to_none=True)
            parts.total.backward()
            optimiser.step()
            total_loss += float(parts.total.detach()) * idx.numel()
            total_nll += parts.nll * idx.numel()
            correct += int((predictions_of(model, outputs) == yb).sum())
            if is_spiking(model):
                hidden_spikes += float(outputs[1].detach().sum())
            batches_done += 1
            if progress is not None:
                progress(batches_done, total_batches, f"epoch {epoch}/{settings.epochs}")
        test_acc = accuracy(model, test[0], test[1], forward=forward)
        val_acc = accuracy(model, val[0], val[1], forward=forward) if val is not None and val[0].shape[0] else None
        record = EpochRecord(epoch, total_loss / n, total_nll / n, correct / n, test_acc, val_acc,
                             hidden_spikes / n if is_spiking(model) else None, time.perf_counter() - started)
        history.epochs.append(record)
        if scheduler is not None:
            scheduler.step(record.loss)
        metric = {"test": test_acc, "val": val_acc, "last": float(epoch)}[select]
        if metric > best_metric:   # strict: ties keep the earlier epoch
            best_metric = metric
            best_state = copy.deepcopy(model.state_dict())
            history.best_epoch = epoch
            history.best_test_accuracy = test_acc
            history.best_val_accuracy = val_acc
        if on_epoch is not None:
            on_epoch(record)
    if best_state is not None:
        model.load_state_dict(best_state)


def build_model(kind: str, **config) -> nn.Module:
    """A zoo model by kind ("rsnn", "ffsnn", "lstm", "elstm", or a buffered classifier "fcn", "resnet",
    "encoder", "tcnn", "inception") from config keyword arguments."""
    from snncc.models import LSTMConfig, SNNConfig
    from snncc.models.baselines import BASELINE_KINDS, BaselineConfig, BufferedClassifier

    if kind in BASELINE_KINDS:
        return BufferedClassifier(BaselineConfig(kind=kind, **config))
    if kind in ("rsnn", "ffsnn"):
        return SpikingClassifier(SNNConfig(recurrent=(kind == "rsnn"), **config))
    return LSTMClassifier(LSTMConfig(signal="spikes" if kind == "elstm" else "analog", **config))
