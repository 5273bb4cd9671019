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
from snncc.limits import check_memory, check_real, positive_number, whole_number
from snncc.models import LSTMClassifier, LSTMConfig, SNNConfig, SpikingClassifier
from snncc.models.snn import UPDATE_ORDERS
from snncc.models.baselines import BASELINE_KINDS, BaselineConfig, BufferedClassifier

FORMAT = "snncc-checkpoint"
# training bookkeeping that stays in the checkpoint and never travels into graphs or artefacts
TRAINING_ONLY_METADATA = ("split_assignment",)
VERSION = 1
KINDS = ("rsnn", "ffsnn", "lstm", "elstm") + BASELINE_KINDS
# sizes a buffered classifier's record may ask for (checked before anything is allocated): the
# largest (Encoder, 2048 steps, 256 classes) stays under 40 M parameters
BASELINE_BOUNDS = {"n_inputs": (1, 256), "n_steps": (9, 2048), "n_outputs": (2, 256), "longest_kernel": (4, 128)}


def _checked_baseline(arch: dict, source: str) -> BaselineConfig:
    """A buffered classifier's config from its record, each size a whole number within bounds."""
    for key, (lo, hi) in BASELINE_BOUNDS.items():
        if key in arch:
            value = arch[key]
            if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
                raise SnnccError(f"must be a whole number in [{lo}, {hi}], got {value!r}", file=source,
                                 field=f"architecture.{key}")
    dt = arch.get("dt", 0.025)
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not 0 < dt <= 1:
        raise SnnccError(f"must be a number in (0, 1] seconds, got {dt!r}", file=source, field="architecture.dt")
    return BaselineConfig(**arch)


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


SIZE_FIELDS = ("n_inputs", "n_hidden", "n_outputs", "input_copies")
POSITIVE_FIELDS = ("tau_mem", "tau_syn", "dt", "threshold", "scale")


def parameter_count(kind: str, arch: dict[str, Any]) -> int:
    """Weights the architecture declares (Python ints: no overflow, nothing allocated)."""
    n_in, n_h, n_out = (int(arch.get(k, d)) for k, d in zip(("n_inputs", "n_hidden", "n_outputs"), _defaults(kind)))
    if kind in ("rsnn", "ffsnn"):
        k = int(arch.get("input_copies", SNNConfig.input_copies))
        return n_in * k * n_h + n_h * n_out + (n_h * n_h if arch.get("recurrent", True) else 0)
    return 4 * n_h * (n_in + n_h) + 8 * n_h + n_h * n_out + n_out


def _defaults(kind: str) -> tuple[int, int, int]:
    cfg = SNNConfig if kind in ("rsnn", "ffsnn") else LSTMConfig
    return cfg.n_inputs, cfg.n_hidden, cfg.n_outputs


def check_architecture(kind: str, arch: dict[str, Any], source: str = "<checkpoint>") -> None:
    """Sizes are whole numbers >= 1, times and thresholds positive and finite, the weights fit in memory
    (``snncc.limits``) -- all checked before the module is built."""
    for key in SIZE_FIELDS:
        if key in arch and (key != "input_copies" or kind in ("rsnn", "ffsnn")):
            whole_number(arch[key], file=source, field=f"architecture.{key}")
    for key in POSITIVE_FIELDS:
        if key in arch and (key in ("dt",) or kind in ("rsnn", "ffsnn")):
            positive_number(arch[key], file=source, field=f"architecture.{key}")
    if kind in ("rsnn", "ffsnn") and not isinstance(arch.get("recurrent", True), bool):
        raise SnnccError(f"must be true or false, got {arch['recurrent']!r}", file=source, field="architecture.recurrent")
    if kind in ("rsnn", "ffsnn") and "order" in arch and arch["order"] not in UPDATE_ORDERS:
        raise SnnccError(f"must be one of {', '.join(UPDATE_ORDERS)}, got {arch['order']!r}", file=source,
                         field="architecture.order")
    if kind in ("lstm", "elstm") and "signal" in arch and arch["signal"] not in ("analog", "spikes"):
        raise SnnccError(f"must be 'analog' or 'spikes', got {arch['signal']!r}", file=source, field="architecture.signal")
    n = parameter_count(kind, arch)
    check_memory(8 * n, f"the architecture's {n:,} weights (float64)", file=source, field="architecture")


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
    if kind not in BASELINE_KINDS:   # a buffered classifier's record is bounded by _checked_baseline
        check_architecture(kind, arch, source)
    try:
        if kind in BASELINE_KINDS:
            module: torch.nn.Module = BufferedClassifier(_checked_baseline({"kind": kind, **arch}, source))
        elif kind in ("rsnn", "ffsnn"):
            module = SpikingClassifier(SNNConfig(**arch))
        else:
            module = LSTMClassifier(LSTMConfig(**arch))
    except (TypeError, ValueError) as ex:
        raise SnnccError(f"architecture record does not describe a {kind} ({ex})", file=source, field="architecture") from None
    state = obj["state_dict"]
    for key, value in state.items():
        if isinstance(value, torch.Tensor):
            check_real(value, file=source, field=f"state_dict.{key}")
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
