"""snncc checkpoints: ``{"format", "version", "architecture", "state_dict", "metadata"}``.

Plain containers and tensors only, so ``torch.load(weights_only=True)`` reads them. The
architecture record rebuilds the zoo module (``snncc.models``); metadata carries dt, encoding,
classes and training facts.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import torch

from snncc.atomic import write_bytes_atomic
from snncc.errors import SnnccError
from snncc.models import LSTMClassifier, LSTMConfig, SNNConfig, SpikingClassifier

FORMAT = "snncc-checkpoint"
# training bookkeeping that stays in the checkpoint and never travels into graphs or artefacts
TRAINING_ONLY_METADATA = ("split_assignment",)
VERSION = 1
KINDS = ("rsnn", "ffsnn", "lstm", "elstm")


def is_checkpoint(obj: Any) -> bool:
    return isinstance(obj, dict) and obj.get("format") == FORMAT


def save_checkpoint(module: torch.nn.Module, path: str | Path, metadata: dict[str, Any] | None = None) -> None:
    """Write ``module`` (a zoo model) as an snncc checkpoint, atomically."""
    record = {
        "format": FORMAT,
        "version": VERSION,
        "architecture": module.architecture(),
        "state_dict": {k: v.detach().cpu().clone() for k, v in module.state_dict().items()},
        "metadata": dict(metadata or {}),
    }
    buf = io.BytesIO()
    torch.save(record, buf)
    write_bytes_atomic(path, buf.getvalue())


def module_from_checkpoint(obj: dict[str, Any], source: str = "<checkpoint>") -> torch.nn.Module:
    """Rebuild the zoo module a checkpoint describes and load its weights (strictly)."""
    if obj.get("version") != VERSION:
        raise SnnccError(f"unsupported checkpoint version {obj.get('version')!r} (this snncc reads {VERSION})",
                         file=source, field="version")
    for key in ("architecture", "state_dict"):
        if not isinstance(obj.get(key), dict):
            raise SnnccError("missing or not a dict", file=source, field=key)
    arch = dict(obj["architecture"])
    kind = arch.pop("kind", None)
    if kind not in KINDS:
        raise SnnccError(f"unknown model kind {kind!r} (known: {', '.join(KINDS)})", file=source, field="architecture.kind")
    try:
        if kind in ("rsnn", "ffsnn"):
            module: torch.nn.Module = SpikingClassifier(SNNConfig(**arch))
        else:
            module = LSTMClassifier(LSTMConfig(**arch))
    except (TypeError, ValueError) as ex:
        raise SnnccError(f"architecture record does not describe a {kind} ({ex})", file=source, field="architecture") from None
    state = obj["state_dict"]
    for key, value in state.items():
        if isinstance(value, torch.Tensor) and value.is_floating_point() and not torch.all(torch.isfinite(value)):
            raise SnnccError("contains NaN or Inf; weights must be finite", file=source, field=f"state_dict.{key}")
    try:
        module.load_state_dict(state, strict=True)
    except RuntimeError as ex:
        first = str(ex).strip().splitlines()
        detail = first[1].strip() if len(first) > 1 else first[0]
        raise SnnccError(f"weights do not fit the architecture: {detail}", file=source, field="state_dict") from None
    return module


def model_metadata(obj: dict[str, Any]) -> dict[str, Any]:
    """The checkpoint's metadata that describes the model (training bookkeeping left out)."""
    meta = obj.get("metadata") if isinstance(obj.get("metadata"), dict) else {}
    return {k: v for k, v in meta.items() if k not in TRAINING_ONLY_METADATA}
