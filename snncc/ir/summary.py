"""A plain-data summary of a graph: nodes, sizes, parameters, edges with delays (for reports)."""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Conv, Dense, Input, Readout


def _uniform(arr: np.ndarray) -> float | list[float]:
    return float(arr[0]) if arr.size and np.all(arr == arr[0]) else [float(a) for a in arr]


def node_summary(g: Graph, name: str) -> dict[str, Any]:
    op = g.node(name)
    row: dict[str, Any] = {"name": name, "kind": op.kind, "size": op.size}
    if isinstance(op, Input):
        row["signal"] = op.signal
    elif isinstance(op, Dense):
        row.update(shape=list(op.weight.shape), parameters=int(op.weight.size + (0 if op.bias is None else op.bias.size)),
                   max_abs_weight=float(np.max(np.abs(op.weight))), bias=op.bias is not None)
    elif isinstance(op, Conv):
        row.update(in_shape=list(op.in_shape), out_shape=list(op.out_shape), kernel=list(op.weight.shape),
                   stride=list(op.stride), padding=list(op.padding), dilation=list(op.dilation), groups=op.groups,
                   parameters=int(op.weight.size + (0 if op.bias is None else op.bias.size)),
                   max_abs_weight=float(np.max(np.abs(op.weight))), bias=op.bias is not None)
    elif isinstance(op, LIF):
        alpha, beta = op.decays(g.dt)
        row.update(tau_syn=_uniform(op.tau_syn), tau_mem=_uniform(op.tau_mem), threshold=_uniform(op.threshold),
                   alpha=_uniform(alpha), beta=_uniform(beta), reset=op.reset, refractory=op.refractory,
                   discretisation=op.discretisation, bias=None if op.bias is None else op.bias_placement)
    elif isinstance(op, LSTM):
        n_bias = sum(b.size for b in (op.bias_ih, op.bias_hh) if b is not None)
        row.update(input_size=op.input_size, hidden_size=op.hidden_size,
                   parameters=int(op.weight_ih.size + op.weight_hh.size + n_bias),
                   bias_vectors=sum(b is not None for b in (op.bias_ih, op.bias_hh)))
    elif isinstance(op, Readout):
        row["mode"] = op.mode
    row["inputs"] = [{"from": p, "delay": g.delay(p, name), "port": g.port(p, name)} for p in g.predecessors(name)]
    return row


def graph_summary(g: Graph) -> dict[str, Any]:
    nodes = [node_summary(g, n) for n in g]
    return {
        "name": g.name,
        "dt": g.dt,
        "nodes": nodes,
        "parameters": int(sum(r.get("parameters", 0) for r in nodes)),
        "neurons": int(sum(r["size"] for r in nodes if r["kind"] == "LIF")),
        "metadata": g.metadata,
    }
