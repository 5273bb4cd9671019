"""``snncc train`` as a function: one of the paper's models trained with its preset, written as a checkpoint."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Callable, Mapping, Sequence

from snncc.verbs import VerbProgress

if TYPE_CHECKING:
    from snncc.training.pipeline import TrainResult
    from snncc.training.trainer import EpochRecord


def _overrides(overrides: Sequence[str] | Mapping[str, object] | None) -> dict:
    from snncc.training.presets import parse_overrides

    if isinstance(overrides, Mapping):
        return parse_overrides([f"{k}={v}" for k, v in overrides.items()])
    return parse_overrides(list(overrides) if overrides else None)


def train(model: str, *, data: str | os.PathLike, output: str | os.PathLike, threshold: int = 1, epochs: int = 300,
          subset: int | None = None, seed: int = 0, order: str = "spytorch", val_fraction: float = 0.0,
          qat_from: str | os.PathLike | None = None, qat_epochs: int = 3,
          overrides: Sequence[str] | Mapping[str, object] | None = None, params: str | os.PathLike | None = None,
          batch_size: int | None = None, lr: float | None = None, device: str = "auto", threads: int = 1,
          progress: VerbProgress | None = None, on_epoch: Callable[[EpochRecord], None] | None = None) -> TrainResult:
    """Train ``model`` (rsnn, ffsnn, lstm, elstm, fcn, resnet, encoder, tcnn, inception) on ``data``
    (an encoded .npz or a directory of published pickles) and write the checkpoint ``output``.

    ``qat_from``: quantization-aware fine-tuning of that rsnn/ffsnn checkpoint instead (same split);
    ``overrides``: preset values (``--set``), ``["tau_mem=0.05"]`` or ``{"tau_mem": 0.05}``;
    ``params``: the authors' parameters file instead of the preset; ``threads``: torch CPU threads
    during the call. ``progress(done, total, "epoch e/E")``: called after each batch once the data
    are loaded, ``done`` counting batches over all epochs; ``on_epoch(record)``: called after each
    epoch with its ``snncc.training.trainer.EpochRecord`` (the CLI prints its line); None: silent.
    """
    import torch

    from snncc.atomic import preflight
    from snncc.errors import SnnccError
    from snncc.training.pipeline import TrainRequest, finetune, train as train_model

    if threads < 1:
        raise SnnccError("must be >= 1", field="--threads")
    if batch_size is not None and batch_size < 1:
        raise SnnccError("must be >= 1", field="--batch-size")
    preflight(output)   # an output that cannot be written is refused now, not after the training
    req = TrainRequest(kind=str(model), data=str(data), output=str(output), threshold=threshold, epochs=epochs,
                       subset=subset, seed=seed, order=str(order), val_fraction=val_fraction, batch_size=batch_size,
                       overrides=_overrides(overrides), params_file=str(params) if params else None,
                       qat_from=str(qat_from) if qat_from else None, qat_epochs=qat_epochs, device=device, lr=lr)
    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        run = finetune if req.qat_from else train_model
        return run(req, progress, on_epoch=on_epoch)
    finally:
        torch.set_num_threads(before)
