"""What the Jetson target needs to know about an IR graph before building torch modules from it.

One Input and one Output (the ONNX model has one data input and one data output stream); the
evaluation order is the topological order of the zero-delay edges (as in the reference
simulator); every (node, port) read through an edge with delay d >= 1 keeps a history of its
last ``depth`` outputs. Input copies (metadata ``input_copies`` k, ``base_inputs`` C) are applied
inside the model: the model takes C channels and feeds ``concat([x] * k)`` to the graph.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Conv, Dense, Input, Output, Readout
from snncc.ir.validate import refuse_spike_rules


@dataclass
class GraphPlan:
    graph: Graph
    order: list[str]                       # zero-delay topological order (the simulator's)
    input_name: str
    output_name: str
    input_copies: int                      # k: the graph's Input has base_inputs * k channels
    base_inputs: int                       # channels the user's data has
    score_mode: str | None                 # spike_count | membrane_max | last | None
    spiking_output: bool                   # the Output carries LIF spikes (0/1)
    history: dict[tuple[str, str], int] = field(default_factory=dict)  # (node, port) -> depth
    has_lif: bool = False

    @property
    def output_width(self) -> int:
        return self.graph.node(self.output_name).size

    @property
    def signal(self) -> str:
        return self.graph.node(self.input_name).signal


def _zero_delay_order(g: Graph) -> list[str]:
    zero = nx.DiGraph()
    zero.add_nodes_from(g.nx.nodes)
    zero.add_edges_from((u, v) for u, v, d, _ in g.edges() if d == 0)
    return list(nx.lexicographical_topological_sort(zero, key=list(g.nx.nodes).index))


def _output_source(g: Graph, output: str) -> tuple[str, str]:
    """Follow the pass-through chain (Output <- Readout <- ...) to the node that makes the values."""
    name, port = output, "spikes"
    while isinstance(g.node(name), (Output, Readout)):
        (pred,) = g.predecessors(name)
        name, port = pred, g.port(pred, name)
    return name, port


def plan_graph(g: Graph) -> GraphPlan:
    """Check the graph is expressible as a Jetson artefact and record how to evaluate it."""
    inputs, outputs = g.of_kind(Input), g.of_kind(Output)
    if len(inputs) != 1:
        raise SnnccError(f"the Jetson target takes graphs with exactly one Input node, this one has {len(inputs)}",
                         field="graph")
    if len(outputs) != 1:
        raise SnnccError(f"the Jetson target takes graphs with exactly one Output node, this one has {len(outputs)}",
                         field="graph")
    for name, op in g.items():
        if not isinstance(op, (Input, Dense, Conv, LIF, LSTM, Readout, Output)):
            raise SnnccError(f"node kind {type(op).__name__} has no Jetson lowering", field=f"node '{name}'")
    refuse_spike_rules(g, "the Jetson lowering")
    in_name, out_name = inputs[0], outputs[0]
    width = g.node(in_name).width
    k = int(g.metadata.get("input_copies", 1) or 1)
    base = int(g.metadata.get("base_inputs", width // max(k, 1)) or 0)
    if k < 1 or base * k != width:
        k, base = 1, width
    readouts = g.of_kind(Readout)
    src, port = _output_source(g, out_name)
    src_op = g.node(src)
    spiking = isinstance(src_op, LIF) and port == "spikes"
    if readouts:
        mode = g.node(readouts[0]).mode
    else:
        mode = "spike_count" if spiking else "last"
    history: dict[tuple[str, str], int] = {}
    for u, v, d, p in g.edges():
        if d >= 1:
            history[(u, p)] = max(history.get((u, p), 0), d)
    return GraphPlan(graph=g, order=_zero_delay_order(g), input_name=in_name, output_name=out_name,
                     input_copies=k, base_inputs=base, score_mode=mode, spiking_output=spiking,
                     history=dict(sorted(history.items(), key=lambda kv: (list(g.nx.nodes).index(kv[0][0]), kv[0][1]))),
                     has_lif=bool(g.of_kind(LIF)))
