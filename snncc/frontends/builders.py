"""Build IR graphs for the model families every frontend produces (one builder per family)."""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Dense, Input, Output, Readout
from snncc.models.snn import UPDATE_ORDERS

BRAILLE_CLASSES = ["Space"] + [chr(c) for c in range(ord("A"), ord("Z") + 1)]


def snn_graph(
    w_in: np.ndarray,
    w_out: np.ndarray,
    v_rec: np.ndarray | None,
    *,
    dt: float,
    tau_syn: float,
    tau_mem: float,
    threshold: float = 1.0,
    order: str = "spytorch",
    input_copies: int = 1,
    metadata: dict[str, Any] | None = None,
    name: str = "rsnn",
) -> Graph:
    """inputs -> Dense(W_in) -> LIF hidden (<-> Dense(V_rec)) -> Dense(W_out) -> LIF out -> spike-count readout.

    Weights arrive in the authors' (in, out) orientation (``h = x @ W``) and are stored (out, in).
    ``order`` picks the update order (delays and refractory period) from ``UPDATE_ORDERS``.
    """
    timing = UPDATE_ORDERS[order]
    w_in, w_out = np.asarray(w_in, np.float64), np.asarray(w_out, np.float64)
    n_in, n_hidden = w_in.shape
    n_out = w_out.shape[1]
    lif = dict(tau_syn=tau_syn, tau_mem=tau_mem, threshold=threshold, reset="zero",
               refractory=timing["refractory"], discretisation="exp")
    meta = {"update_order": order, "input_copies": int(input_copies),
            "base_inputs": int(n_in // max(int(input_copies), 1)), "readout": "spike_count"}
    meta.update(metadata or {})
    g = Graph(dt, name=name, metadata=meta)
    g.add("input", Input(width=n_in, signal="spikes"))
    g.add("w_in", Dense(weight=w_in.T))
    g.add("hidden", LIF(n=n_hidden, **lif))
    g.add("w_out", Dense(weight=w_out.T))
    g.add("out", LIF(n=n_out, **lif))
    g.add("readout", Readout(width=n_out, mode="spike_count"))
    g.add("output", Output(width=n_out))
    g.connect("input", "w_in", delay=timing["delay_in"])
    g.connect("w_in", "hidden")
    if v_rec is not None:
        g.add("w_rec", Dense(weight=np.asarray(v_rec, np.float64).T))
        g.connect("hidden", "w_rec", delay=timing["delay_rec"])
        g.connect("w_rec", "hidden")
    g.connect("hidden", "w_out", delay=timing["delay_out"])
    g.connect("w_out", "out")
    g.connect("out", "readout")
    g.connect("readout", "output")
    return g


def lstm_graph(
    weight_ih: np.ndarray,
    weight_hh: np.ndarray,
    bias: np.ndarray | None,
    fc_weight: np.ndarray,
    fc_bias: np.ndarray | None,
    *,
    dt: float,
    signal: str,
    metadata: dict[str, Any] | None = None,
    name: str = "lstm",
) -> Graph:
    """inputs -> LSTM (one bias vector) -> Dense on every hidden state -> readout of the last step."""
    g = Graph(dt, name=name, metadata={"readout": "last", **(metadata or {})})
    n_in = np.asarray(weight_ih).shape[1]
    n_out = np.asarray(fc_weight).shape[0]
    g.add("input", Input(width=n_in, signal=signal))
    g.add("lstm", LSTM(weight_ih=weight_ih, weight_hh=weight_hh, bias_ih=bias))
    g.add("fc", Dense(weight=fc_weight, bias=fc_bias))
    g.add("readout", Readout(width=n_out, mode="last"))
    g.add("output", Output(width=n_out))
    g.connect("input", "lstm")
    g.connect("lstm", "fc")
    g.connect("fc", "readout")
    g.connect("readout", "output")
    return g
