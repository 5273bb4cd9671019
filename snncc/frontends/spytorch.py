"""The paper authors' SpyTorch weight lists plus their parameters file.

``[W_in (N_in x N_h), W_out (N_h x N_out), V_rec (N_h x N_h)]`` (RSNN) or ``[W_in, W_out]``
(FFSNN), float tensors in ``(in, out)`` orientation, saved from a GPU (loaded on the CPU).
The model is recorded in the authors' update order (``spytorch``: integrate-then-fire, reset to
zero, refractory 2, edge delays 2 / 3 / 2), so every target can reproduce it as trained.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import torch

from snncc.errors import SnnccError
from snncc.limits import check_real
from snncc.frontends.builders import BRAILLE_CLASSES, snn_graph
from snncc.frontends.params import RECORDING_LENGTH_S, PaperParams, load_params
from snncc.ir.graph import Graph

NAMES = ("W_in", "W_out", "V_rec")


def is_weight_list(obj: Any) -> bool:
    return isinstance(obj, (list, tuple)) and len(obj) in (2, 3) and all(isinstance(t, torch.Tensor) for t in obj)


def weight_list_to_graph(weights: list, params: PaperParams, source: str = "<weights>", order: str = "spytorch") -> Graph:
    arrays = []
    for name, t in zip(NAMES, weights):
        check_real(t, file=source, field=name)
        a = t.detach().to("cpu", torch.float64).numpy()
        if a.ndim != 2:
            raise SnnccError(f"must be a 2-D matrix, got shape {tuple(a.shape)}", file=source, field=name)
        if not np.all(np.isfinite(a)):
            raise SnnccError("contains NaN or Inf; weights must be finite", file=source, field=name)
        arrays.append(a)
    w_in, w_out = arrays[0], arrays[1]
    v_rec = arrays[2] if len(arrays) == 3 else None
    n_in, n_h = w_in.shape
    if w_out.shape[0] != n_h:
        raise SnnccError(f"shapes do not chain: W_in gives {n_h} hidden neurons, W_out expects {w_out.shape[0]} "
                         "(the list is (in, out) oriented)", file=source, field="W_out")
    if v_rec is not None and v_rec.shape != (n_h, n_h):
        raise SnnccError(f"the recurrent matrix must be square ({n_h} x {n_h}), got {v_rec.shape}", file=source, field="V_rec")
    k = params.nb_input_copies
    if n_in % k:
        raise SnnccError(f"W_in has {n_in} inputs, not a multiple of nb_input_copies = {k}", file=source, field="W_in")
    n_out = w_out.shape[1]
    meta = {
        "source_format": "spytorch-weight-list",
        "model_kind": "rsnn" if v_rec is not None else "ffsnn",
        "params": params.as_dict(),
        "recording_length_s": RECORDING_LENGTH_S,
        "encoding": "sigma-delta events, channel = 2*taxel + polarity",
        "classes": (BRAILLE_CLASSES + ["spare"])[:n_out] if n_out in (27, 28) else [str(i) for i in range(n_out)],
    }
    return snn_graph(w_in, w_out, v_rec, dt=params.dt, tau_syn=params.tau_syn, tau_mem=params.tau_mem,
                     threshold=1.0, order=order, input_copies=k, metadata=meta,
                     name="rsnn" if v_rec is not None else "ffsnn")


def load_weight_list(obj: Any, path: Path, params_path: str | Path | None) -> Graph:
    if params_path is None:
        raise SnnccError("a SpyTorch weight list needs its parameters file: pass --params=parameters_thN.txt",
                         file=str(path), field="--params")
    return weight_list_to_graph(list(obj), load_params(params_path), source=str(path))
