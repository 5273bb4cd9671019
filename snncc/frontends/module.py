"""snncc's own torch modules (the model zoo) straight to IR graphs."""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from snncc.errors import SnnccError
from snncc.frontends.builders import BRAILLE_CLASSES, lstm_graph, snn_graph
from snncc.frontends.params import RECORDING_LENGTH_S
from snncc.ir.graph import Graph
from snncc.models import LSTMClassifier, SpikingClassifier


def _np(t: torch.Tensor) -> np.ndarray:
    return t.detach().to("cpu", torch.float64).numpy()


def _classes(n: int) -> list[str]:
    return (BRAILLE_CLASSES + ["spare"])[:n] if n in (27, 28) else [str(i) for i in range(n)]


def graph_from_module(module: torch.nn.Module, metadata: dict[str, Any] | None = None) -> Graph:
    """The IR graph of a zoo module, in the update order it was built (and trained) with."""
    meta = {"model_kind": getattr(getattr(module, "config", None), "kind", None)}
    meta.update(metadata or {})
    if isinstance(module, SpikingClassifier):
        cfg = module.config
        meta.setdefault("recording_length_s", RECORDING_LENGTH_S)
        meta.setdefault("classes", _classes(cfg.n_outputs))
        return snn_graph(
            _np(module.w_in), _np(module.w_out), None if module.v_rec is None else _np(module.v_rec),
            dt=cfg.dt, tau_syn=cfg.tau_syn, tau_mem=cfg.tau_mem, threshold=cfg.threshold,
            order=cfg.order, input_copies=cfg.input_copies, metadata=meta, name=cfg.kind,
        )
    if isinstance(module, LSTMClassifier):
        cfg = module.config
        lstm = module.lstm
        bias = _np(lstm.bias_ih_l0) + _np(lstm.bias_hh_l0)
        meta.setdefault("classes", _classes(cfg.n_outputs))
        return lstm_graph(_np(lstm.weight_ih_l0), _np(lstm.weight_hh_l0), bias,
                          _np(module.fc.weight), _np(module.fc.bias),
                          dt=cfg.dt, signal=cfg.signal, metadata=meta, name=cfg.kind)
    raise SnnccError(f"not a snncc zoo model: {type(module).__name__}", field="module")
