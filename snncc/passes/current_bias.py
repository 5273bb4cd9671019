"""Biases that enter a population's current, grouped by the IR step from which they arrive.

A LIF's current receives, besides weighted spikes, constant terms:

    I[t] += b_lif                     for t >= 0   (LIF bias placed on the current)
    I[t] += b_k                       for t >= d_k (Dense k's bias, d_k = delay of the edge Dense k -> LIF;
                                                    before d_k the Dense's output has not arrived)

``current_biases`` sums the terms that start at the same step into one ``BiasTerm``. A target
without a current-bias register (Loihi 1: compartment biases enter the voltage) lowers each
term as a synapse from an always-on source; ``restore_biases`` writes terms back into a graph.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense


@dataclass
class BiasTerm:
    start: int                  # first IR step at which the term is added to the current
    vector: np.ndarray          # (n,) float, the sum of the origins' biases
    origins: tuple[str, ...]    # the nodes it came from (the LIF itself, or Dense nodes)


def current_biases(graph: Graph, lif: str) -> list[BiasTerm]:
    """The current biases of population ``lif``, one term per start step, sorted by start."""
    op = graph.node(lif)
    by_start: dict[int, BiasTerm] = {}

    def add(start: int, vector: np.ndarray, origin: str) -> None:
        term = by_start.get(start)
        if term is None:
            by_start[start] = BiasTerm(start, np.asarray(vector, np.float64).copy(), (origin,))
        else:
            term.vector = term.vector + vector
            term.origins = term.origins + (origin,)

    if isinstance(op, LIF) and op.bias is not None and op.bias_placement == "current":
        add(0, op.bias, lif)
    for pred in graph.predecessors(lif):
        dense = graph.node(pred)
        if isinstance(dense, Dense) and dense.bias is not None:
            add(graph.delay(pred, lif), np.broadcast_to(dense.bias, (op.n,)), pred)
    return [by_start[k] for k in sorted(by_start)]


def max_abs_bias(graph: Graph, lif: str) -> float:
    """max |b| over the current-bias terms of ``lif`` (0 without any)."""
    return max((float(np.max(np.abs(t.vector))) for t in current_biases(graph, lif) if t.vector.size), default=0.0)


def restore_biases(graph: Graph, lif: str, terms: list[BiasTerm]) -> None:
    """Write ``terms`` (e.g. quantized) back into ``graph`` in place, each on its first origin.

    The other origins of a term lose their bias; the first origin has the term's start as its
    delay (or is the LIF itself, start 0), so the graph's meaning is kept.
    """
    for term in terms:
        for k, origin in enumerate(term.origins):
            node = graph.node(origin)
            value = np.asarray(term.vector, np.float64).copy() if k == 0 else None
            node.bias = value
            if isinstance(node, LIF) and value is not None:
                node.bias_placement = "current"
