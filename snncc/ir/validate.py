"""Graph validation: a list of small rules, each raising SnnccError naming the node and the rule.

``validate(graph)`` runs them all in order and returns the graph unchanged, so it chains.
"""

from __future__ import annotations

import math
from typing import Callable

import networkx as nx
import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import (
    BIAS_PLACEMENTS,
    DISCRETISATIONS,
    FIRE_TESTS,
    INPUT_KINDS,
    LIF,
    LSTM,
    READOUT_MODES,
    RESETS,
    Conv,
    Dense,
    Input,
    Node,
    Output,
    Readout,
)

Rule = Callable[[Graph], None]


def _fail(rule: str, field: str) -> None:
    raise SnnccError(rule, field=field)


def rule_dt(g: Graph) -> None:
    """The graph states a global time step dt > 0 (seconds)."""
    if g.dt is None:
        _fail("the graph has no dt; the frontend must set one (e.g. --dt)", "dt")
    if not (math.isfinite(g.dt) and g.dt > 0):
        _fail(f"dt must be a positive finite number of seconds, got {g.dt}", "dt")


def rule_has_inputs_and_outputs(g: Graph) -> None:
    """At least one Input and one Output node."""
    if not g.of_kind(Input):
        _fail("the graph has no Input node", "graph")
    if not g.of_kind(Output):
        _fail("the graph has no Output node", "graph")
    if len(g.of_kind(Readout)) > 1:
        _fail("a graph has at most one Readout", "graph")


def _finite(name: str, field: str, arr: np.ndarray | None) -> None:
    if arr is None:
        return
    if not np.all(np.isfinite(arr)):
        bad = "NaN" if np.any(np.isnan(arr)) else "Inf"
        _fail(f"contains {bad}; weights and parameters must be finite", f"node '{name}'.{field}")


def _check_input(name: str, op: Input) -> None:
    if op.width < 1:
        _fail("width must be >= 1", f"node '{name}'.width")
    if op.signal not in INPUT_KINDS:
        _fail(f"signal must be one of {INPUT_KINDS}", f"node '{name}'.signal")


def _check_dense(name: str, op: Dense) -> None:
    if op.weight.ndim != 2 or 0 in op.weight.shape:
        _fail(f"weight must be a non-empty 2-D (out, in) matrix, got shape {op.weight.shape}", f"node '{name}'.weight")
    _finite(name, "weight", op.weight)
    if op.bias is not None and op.bias.shape != (op.weight.shape[0],):
        _fail(f"bias must have shape ({op.weight.shape[0]},), got {op.bias.shape}", f"node '{name}'.bias")
    _finite(name, "bias", op.bias)


def _check_lif(name: str, op: LIF) -> None:
    if op.n < 1:
        _fail("n must be >= 1", f"node '{name}'.n")
    for fname in ("tau_syn", "tau_mem", "threshold"):
        arr = getattr(op, fname)
        if arr.shape != (op.n,):
            _fail(f"must have one value or {op.n} values, got shape {arr.shape}", f"node '{name}'.{fname}")
        if np.any(np.isnan(arr)):
            _fail("contains NaN", f"node '{name}'.{fname}")
    for fname in ("tau_syn", "tau_mem"):
        arr = getattr(op, fname)
        if np.any(arr <= 0) or not np.all(np.isfinite(arr)):
            _fail("time constants must be positive and finite (seconds)", f"node '{name}'.{fname}")
    if np.any(op.threshold <= 0):
        _fail("threshold must be > 0 (+inf for a non-spiking integrator)", f"node '{name}'.threshold")
    if op.reset not in RESETS:
        _fail(f"reset must be one of {RESETS}", f"node '{name}'.reset")
    if op.discretisation not in DISCRETISATIONS:
        _fail(f"discretisation must be one of {DISCRETISATIONS}", f"node '{name}'.discretisation")
    if op.refractory < 1:
        _fail("refractory must be >= 1 step (1 = no refractory period)", f"node '{name}'.refractory")
    if op.bias_placement not in BIAS_PLACEMENTS:
        _fail(f"bias_placement must be one of {BIAS_PLACEMENTS}", f"node '{name}'.bias_placement")
    if op.bias is not None and op.bias.shape != (op.n,):
        _fail(f"bias must have shape ({op.n},)", f"node '{name}'.bias")
    _finite(name, "bias", op.bias)
    if op.max_spikes < 1:
        _fail(f"max_spikes must be >= 1 spike per step, got {op.max_spikes}", f"node '{name}'.max_spikes")
    if op.fire_test not in FIRE_TESTS:
        _fail(f"fire_test must be one of {FIRE_TESTS}", f"node '{name}'.fire_test")


def _check_lstm(name: str, op: LSTM) -> None:
    if op.weight_hh.ndim != 2 or op.weight_ih.ndim != 2:
        _fail("LSTM weights must be 2-D", f"node '{name}'.weight_ih")
    h = op.weight_hh.shape[1]
    if op.weight_hh.shape != (4 * h, h):
        _fail(f"weight_hh must have shape (4H, H), got {op.weight_hh.shape}", f"node '{name}'.weight_hh")
    if op.weight_ih.shape[0] != 4 * h:
        _fail(f"weight_ih must have 4H = {4 * h} rows, got {op.weight_ih.shape[0]}", f"node '{name}'.weight_ih")
    for fname in ("weight_ih", "weight_hh", "bias_ih", "bias_hh"):
        arr = getattr(op, fname)
        if arr is not None and fname.startswith("bias") and arr.shape != (4 * h,):
            _fail(f"must have shape ({4 * h},)", f"node '{name}'.{fname}")
        _finite(name, fname, arr)


def _check_readout(name: str, op: Readout) -> None:
    if op.mode not in READOUT_MODES:
        _fail(f"mode must be one of {READOUT_MODES}", f"node '{name}'.mode")


def _check_conv(name: str, op: Conv) -> None:
    where = f"node '{name}'"
    dims = op.spatial_dims
    if not 1 <= dims <= 3 or 0 in op.weight.shape:
        _fail(f"weight must be (out, in/groups, *kernel) with 1 to 3 kernel dims, got shape {op.weight.shape}",
              f"{where}.weight")
    _finite(name, "weight", op.weight)
    if len(op.in_shape) != dims + 1 or min(op.in_shape) < 1:
        _fail(f"in_shape must be (channels, {dims} spatial size(s)), all >= 1, got {op.in_shape}", f"{where}.in_shape")
    if op.groups < 1 or op.weight.shape[0] % op.groups:
        _fail(f"groups must be >= 1 and divide the {op.weight.shape[0]} output channels", f"{where}.groups")
    if op.in_shape[0] != op.weight.shape[1] * op.groups:
        _fail(f"{op.in_shape[0]} input channels, but weight has {op.weight.shape[1]} per group x {op.groups} groups",
              f"{where}.in_shape")
    for fname, low in (("stride", 1), ("dilation", 1), ("padding", 0)):
        if len(getattr(op, fname)) != dims or min(getattr(op, fname)) < low:
            _fail(f"must be {dims} integer(s) >= {low}", f"{where}.{fname}")
    if min(op.out_shape[1:]) < 1:
        _fail(f"the kernel (dilated) does not fit the padded input: output shape {op.out_shape}", f"{where}.weight")
    if op.bias is not None and op.bias.shape != (op.weight.shape[0],):
        _fail(f"bias must have one value per output channel ({op.weight.shape[0]},)", f"{where}.bias")
    _finite(name, "bias", op.bias)


NODE_CHECKS: dict[type[Node], Callable] = {
    Input: _check_input,
    Dense: _check_dense,
    Conv: _check_conv,
    LIF: _check_lif,
    LSTM: _check_lstm,
    Readout: _check_readout,
    Output: lambda name, op: None,
}


def rule_node_parameters(g: Graph) -> None:
    """Every node's own parameters are well-formed and finite."""
    for name, op in g.items():
        check = NODE_CHECKS.get(type(op))
        if check is None:
            _fail(f"unknown node type {type(op).__name__}", f"node '{name}'")
        check(name, op)


def refuse_spike_rules(g: Graph, what: str) -> None:
    """For a consumer that implements only the standard spike rule (one spike per step, V > theta):
    refuse a graph with any LIF whose ``max_spikes`` or ``fire_test`` differ, in one line."""
    for name, op in g.items():
        if isinstance(op, LIF) and not op.standard_spikes:
            _fail(f"{what} fires at most one spike per step on V > threshold; this population fires up to "
                  f"{op.max_spikes} per step on V {op.fire_test} threshold", f"node '{name}'")


def rule_edge_delays(g: Graph) -> None:
    """Every edge has an integer delay >= 0 (steps); voltage ports only leave LIF nodes."""
    for u, v, d, port in g.edges():
        if d < 0:
            _fail(f"delay must be >= 0 steps, got {d}", f"edge {u}->{v}")
        if port == "voltage" and not isinstance(g.node(u), LIF):
            _fail("only a LIF population can send its voltage", f"edge {u}->{v}")


def rule_fan_in(g: Graph) -> None:
    """Inputs have no predecessors; Dense, Conv, LSTM, Readout, Output have exactly one; LIF >= 1."""
    for name, op in g.items():
        preds = g.predecessors(name)
        if isinstance(op, Input):
            if preds:
                _fail("an Input node has no incoming edges", f"node '{name}'")
        elif isinstance(op, LIF):
            if not preds:
                _fail("a LIF population needs at least one incoming projection", f"node '{name}'")
        elif len(preds) != 1:
            _fail(f"a {op.kind} node takes exactly one input, it has {len(preds)}", f"node '{name}'")
        if isinstance(op, Output) and g.successors(name):
            _fail("an Output node has no outgoing edges", f"node '{name}'")


def _expected_in_width(op: Node) -> int:
    if isinstance(op, (Dense, Conv)):
        return op.in_size
    if isinstance(op, LSTM):
        return op.input_size
    return op.size


def rule_shapes_chain(g: Graph) -> None:
    """Each edge's source width equals what its destination expects."""
    for u, v, _, _ in g.edges():
        got, want = g.node(u).size, _expected_in_width(g.node(v))
        if got != want:
            _fail(f"shapes do not chain: '{u}' gives {got} values, '{v}' expects {want}", f"edge {u}->{v}")


def rule_cycles(g: Graph) -> None:
    """Every cycle passes through a LIF population and contains an edge with delay >= 1."""
    zero_delay = nx.DiGraph()
    zero_delay.add_nodes_from(g.nx.nodes)
    zero_delay.add_edges_from((u, v) for u, v, d, _ in g.edges() if d == 0)
    if not nx.is_directed_acyclic_graph(zero_delay):
        cycle = nx.find_cycle(zero_delay)
        path = "->".join([cycle[0][0]] + [e[1] for e in cycle])
        _fail("a cycle needs at least one edge with delay >= 1 (else the loop is algebraic)", f"cycle {path}")
    without_lif = g.nx.subgraph([n for n, op in g.items() if not isinstance(op, LIF)])
    if not nx.is_directed_acyclic_graph(without_lif):
        cycle = nx.find_cycle(without_lif)
        path = "->".join([cycle[0][0]] + [e[1] for e in cycle])
        _fail("a cycle must pass through a LIF population", f"cycle {path}")


RULES: list[Rule] = [
    rule_dt,
    rule_has_inputs_and_outputs,
    rule_node_parameters,
    rule_edge_delays,
    rule_fan_in,
    rule_shapes_chain,
    rule_cycles,
]


def validate(g: Graph) -> Graph:
    """Run every rule; raise SnnccError at the first one broken; return ``g``."""
    for rule in RULES:
        rule(g)
    return g
