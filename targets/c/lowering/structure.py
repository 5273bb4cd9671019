"""What an IR graph asks of the C target, in float: populations, projections and biases, nothing changed.

The C runs the IR's semantics as stated (``snncc.ir.simulate``): every LIF population is updated once per step
in the IR's schedule (the topological order of zero-delay edges); what reaches a population's current is, per
path from a spike source (the Input or a LIF population) through stateless linear nodes (Dense, Conv), the
product of their matrices applied to the source's spikes ``d`` steps earlier, ``d`` the sum of the path's edge
delays; a linear node's bias reaches it, through the rest of the path, from the step equal to the delays after
that node (before its data arrive the node already emits its bias, as the reference does).

Projections with the same source and delay are summed into one matrix (exact in float). What the C target
cannot express is refused in one line naming the node and why: an LSTM, an analog input, more than one input,
a voltage port, a readout that is not a spike count, an output that is not a population's spikes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LINEAR, LSTM, Conv, Input, Output, Readout


@dataclass
class FloatPopulation:
    name: str
    op: LIF
    alpha: np.ndarray
    beta: np.ndarray
    bias_v: np.ndarray | None
    bias_i: list[tuple[int, np.ndarray]] = field(default_factory=list)    # (start step, vector)


@dataclass
class FloatProjection:
    source: int                      # -1: the input; else a population index
    target: int
    delay: int
    matrix: object                   # scipy.sparse csr (n_target, n_source), float64
    origin: str


@dataclass
class Structure:
    dt: float
    input_name: str
    inputs: int
    populations: list[FloatPopulation]
    projections: list[FloatProjection]
    output: int
    readout: str | None


def _refuse(rule: str, node: str) -> SnnccError:
    return SnnccError(rule, field=f"node '{node}'")


def _matrix(op):
    import scipy.sparse as sp

    if isinstance(op, Conv):
        from snncc.ir.conv import conv_matrix

        return sp.csr_matrix(conv_matrix(op), dtype=np.float64)
    return sp.csr_matrix(np.asarray(op.weight, np.float64))


def _bias_vector(op) -> np.ndarray | None:
    if op.bias is None:
        return None
    if isinstance(op, Conv):
        from snncc.ir.conv import conv_bias_vector

        return np.asarray(conv_bias_vector(op), np.float64)
    return np.broadcast_to(np.asarray(op.bias, np.float64), (op.size,)).copy()


def schedule(graph: Graph) -> list[str]:
    """The IR's update order (``snncc.ir.simulate``: lexicographic topological order of zero-delay edges)."""
    import networkx as nx

    zero = nx.DiGraph()
    zero.add_nodes_from(graph.nx.nodes)
    zero.add_edges_from((u, v) for u, v, d, _ in graph.edges() if d == 0)
    order = list(graph.nx.nodes)
    return list(nx.lexicographical_topological_sort(zero, key=order.index))


def refuse_unsupported(graph: Graph) -> None:
    """One line for the first node or edge the C target cannot express."""
    inputs = graph.of_kind(Input)
    if len(inputs) != 1:
        raise SnnccError(f"the C target takes one Input node, this graph has {len(inputs)}", field="inputs")
    for name, op in graph.items():
        if isinstance(op, LSTM):
            raise _refuse("an LSTM has no spiking integer form on the C target (it runs on --target jetson)", name)
        if isinstance(op, Input) and op.signal != "spikes":
            raise _refuse("the C target takes 0/1 spike inputs, this Input is analog", name)
        if isinstance(op, Readout) and op.mode != "spike_count":
            raise _refuse(f"the C target reads out spike counts; this Readout decides by '{op.mode}'", name)
        if isinstance(op, LIF) and op.max_spikes > 255:
            raise _refuse(f"fires up to {op.max_spikes} spikes per step; the C target's events carry at most 255", name)
    for u, v, _, port in graph.edges():
        if port != "spikes":
            raise SnnccError(f"carries a LIF's {port}; the C target delivers spikes only", field=f"edge {u}->{v}")


def _readout(graph: Graph) -> tuple[str, str | None]:
    """(the LIF whose spikes are the outputs, the Readout node or None)."""
    readouts = graph.of_kind(Readout)
    if readouts:
        (pred,) = graph.predecessors(readouts[0])
        if not isinstance(graph.node(pred), LIF):
            raise _refuse("the C target's outputs are a LIF population's spike counts; this Readout reads a "
                          f"{graph.node(pred).kind}", readouts[0])
        return pred, readouts[0]
    for out in graph.of_kind(Output):
        (pred,) = graph.predecessors(out)
        if isinstance(graph.node(pred), LIF):
            return pred, None
        raise _refuse("the C target's outputs are a LIF population's spike counts; this Output reads a "
                      f"{graph.node(pred).kind}", out)
    raise SnnccError("the graph has no Output", field="outputs")


def structure(graph: Graph) -> Structure:
    """The float structure of ``graph`` (module doc); refusals in one line."""
    import scipy.sparse as sp

    refuse_unsupported(graph)
    input_name = graph.of_kind(Input)[0]
    lifs = [n for n in schedule(graph) if isinstance(graph.node(n), LIF)]
    index = {n: i for i, n in enumerate(lifs)}
    out_name, readout = _readout(graph)
    pops: list[FloatPopulation] = []
    grouped: dict[tuple[int, int, int], list] = {}
    for name in lifs:
        op = graph.node(name)
        alpha, beta = op.decays(graph.dt)
        if np.any(np.abs(alpha) > 1) or np.any(np.abs(beta) > 1):
            raise _refuse("a decay factor outside [-1, 1] (dt larger than twice a time constant with Euler steps) "
                          "has no Q16 multiplier", name)
        bias_v = None
        terms: dict[int, np.ndarray] = {}
        if op.bias is not None:
            if op.bias_placement == "voltage":
                bias_v = np.asarray(op.bias, np.float64).copy()
            else:
                terms[0] = np.asarray(op.bias, np.float64).copy()
        pops.append(FloatPopulation(name, op, np.asarray(alpha, np.float64), np.asarray(beta, np.float64), bias_v))

        def walk(node: str, delay: int, through, path: tuple[str, ...]) -> None:
            src = graph.node(node)
            if isinstance(src, (Input, LIF)):
                source = -1 if isinstance(src, Input) else index[node]
                key = (source, index[name], delay)
                grouped.setdefault(key, []).append((through, "->".join((node,) + path)))
                return
            if not isinstance(src, LINEAR):
                raise _refuse(f"feeds population '{name}' but is a {src.kind}; the C target connects populations "
                              "through Dense and Conv nodes only", node)
            m = _matrix(src)
            here = m if through is None else (through @ m).tocsr()
            b = _bias_vector(src)
            if b is not None and np.any(b):
                vec = b if through is None else np.asarray(through @ b).reshape(-1)
                terms[delay] = terms.get(delay, np.zeros(op.n)) + vec
            for pred in graph.predecessors(node):
                walk(pred, delay + graph.delay(pred, node), here, (node,) + path)

        for pred in graph.predecessors(name):
            walk(pred, graph.delay(pred, name), None, (name,))
        pops[-1].bias_i = sorted(terms.items())
    projections = []
    for (source, target, delay), parts in sorted(grouped.items()):
        n_src = graph.node(input_name).size if source < 0 else pops[source].op.n
        total = sp.csr_matrix((pops[target].op.n, n_src), dtype=np.float64)
        for through, _ in parts:
            if through is None:        # a LIF feeding a LIF directly: the identity
                through = sp.identity(pops[target].op.n, format="csr", dtype=np.float64)
            total = total + through
        projections.append(FloatProjection(source, target, delay, total.tocsr(), ", ".join(p for _, p in parts)))
    return Structure(graph.dt, input_name, int(graph.node(input_name).size), pops, projections, index[out_name],
                     readout)


__all__ = ["FloatPopulation", "FloatProjection", "Structure", "structure", "schedule", "refuse_unsupported"]
