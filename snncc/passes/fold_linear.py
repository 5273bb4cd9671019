"""Fold stateless linear maps into one connection matrix per projection (for synapse-matrix targets).

Rules (exact up to float summation order; the result is a new graph):
  * a ``Conv`` becomes a ``Dense`` with its connection matrix (``snncc.ir.conv.conv_matrix``) and
    its bias repeated over the output positions;
  * ``u -> v`` with u, v linear, u feeding only v and v fed only by u, becomes one Dense
    v' = (W_v W_u, W_v b_u + b_v). The delays add: d(pre, u) + d(u, v). When d(u, v) > 0 and u
    has a bias the chain is kept (before the delayed data arrive v sees u's bias alone, which a
    single Dense cannot state).
  * an all-zero bias is dropped (exact; on Loihi a current bias costs an always-on source and
    a timing shift).
Loihi has no convolutional synapse type: a conv layer reaches the chip as this matrix, stored as
the synapses of each core (zeros need none).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snncc.ir.conv import conv_bias_vector, conv_matrix
from snncc.ir.graph import Graph
from snncc.ir.nodes import LINEAR, Conv, Dense


@dataclass
class FoldRecord:
    convs: list[str] = field(default_factory=list)       # Conv nodes expanded to matrices
    zero_biases: list[str] = field(default_factory=list)  # all-zero biases dropped
    merged: list[str] = field(default_factory=list)      # "u+v" chains merged into v

    @property
    def changed(self) -> bool:
        return bool(self.convs or self.merged or self.zero_biases)

    def notes(self) -> list[str]:
        out = []
        if self.convs:
            out.append(f"{len(self.convs)} convolution(s)/pooling(s) expanded to connection matrices: "
                       + ", ".join(self.convs))
        if self.merged:
            out.append("consecutive linear maps merged into one projection: " + ", ".join(self.merged))
        if self.zero_biases:
            out.append("all-zero biases dropped (exact): " + ", ".join(self.zero_biases))
        return out


def _as_sparse(op):
    import scipy.sparse as sp

    if isinstance(op, Conv):
        return conv_matrix(op), conv_bias_vector(op)
    return sp.csr_matrix(op.weight), op.bias


def fold_linear(graph: Graph) -> tuple[Graph, FoldRecord]:
    """``graph`` with every Conv expanded and every mergeable linear chain merged (see module doc).
    Returns ``graph`` itself when there is nothing to fold."""
    record = FoldRecord()
    linear = [n for n, op in graph.items() if isinstance(op, LINEAR)]
    zero = [n for n in linear if graph.node(n).bias is not None and not np.any(graph.node(n).bias)]
    if not any(isinstance(graph.node(n), Conv) for n in linear) and not any(_mergeable(graph, n) for n in linear) \
            and not zero:
        return graph, record
    g = graph.copy()
    for n in zero:
        g.node(n).bias = None
    record.zero_biases = zero
    mats = {n: _as_sparse(g.node(n)) for n in linear}
    record.convs = [n for n in linear if isinstance(g.node(n), Conv)]
    changed = True
    while changed:
        changed = False
        for u in [n for n in g if n in mats]:
            if not _mergeable(g, u):
                continue
            (v,) = g.successors(u)
            (pre,) = g.predecessors(u)
            a_u, b_u = mats[u]
            a_v, b_v = mats[v]
            a = (a_v @ a_u).tocsr()
            b = None
            if b_u is not None:
                b = a_v @ b_u
            if b_v is not None:
                b = b_v if b is None else b + b_v
            delay, port = g.delay(pre, u) + g.delay(u, v), g.port(pre, u)
            g.nx.remove_node(u)
            g.connect(pre, v, delay=delay, port=port)
            mats[v] = (a, None if b is None else np.asarray(b, np.float64).reshape(-1))
            del mats[u]
            record.merged.append(f"{u}+{v}")
            changed = True
            break
    targets = {m.split("+", 1)[1] for m in record.merged}
    for n, (a, b) in mats.items():
        if isinstance(g.node(n), Conv) or n in targets:
            g.nx.nodes[n]["op"] = Dense(weight=a.toarray(), bias=b)
    return g, record


def _mergeable(g: Graph, u: str) -> bool:
    if not isinstance(g.node(u), LINEAR):
        return False
    succ, preds = g.successors(u), g.predecessors(u)
    if len(succ) != 1 or len(preds) != 1 or succ[0] == u:
        return False
    v = succ[0]
    if not isinstance(g.node(v), LINEAR) or g.predecessors(v) != [u]:
        return False
    return g.delay(u, v) == 0 or g.node(u).bias is None
