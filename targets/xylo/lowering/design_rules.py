"""Xylo design rules: small functions, each refusing in one line that names the rule and the numbers.

``GRAPH_RULES`` run on the IR chain before lowering (``check_graph``); a spec is checked by
``XyloSpec`` and its chip limits (``check_spec``). Chip limits come from ``chip.py`` (``XyloChip``);
the real-time estimate is ``estimate/real_time.py``.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit import SnnccError
from snncc.targets.xylo.chip import XyloChip
from snncc.targets.xylo.lowering.structure import Population


def _fail(rule: str, field: str) -> None:
    raise SnnccError(rule, field=field)


# -- on the IR chain ------------------------------------------------------------------------------

def rule_input_channels(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """At most ``chip.max_inputs`` input channels."""
    width = graph.node(pops[0].pre).width
    if width > chip.max_inputs:
        _fail(f"input channels: the model has {width}, {chip.name} has {chip.max_inputs}", f"node '{pops[0].pre}'")


def rule_hidden_layers(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Inputs reach output neurons only through hidden neurons: at least one hidden population."""
    if len(pops) < 2:
        _fail(f"hidden neurons: the model's inputs feed its readout population '{pops[-1].lif}' directly; "
              f"{chip.name}'s inputs reach output neurons only through hidden neurons", "graph")


def rule_hidden_neurons(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """The hidden populations together fit the hidden neurons."""
    n = sum(graph.node(p.lif).n for p in pops[:-1])
    if n > chip.max_hidden:
        _fail(f"hidden neurons: the model needs {n} ({', '.join(f'{p.lif} {graph.node(p.lif).n}' for p in pops[:-1])}), "
              f"{chip.name} has {chip.max_hidden}", "graph")


def rule_output_neurons(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """The readout population fits the output neurons."""
    n = graph.node(pops[-1].lif).n
    if n > chip.max_outputs:
        _fail(f"output neurons: the readout population has {n}, {chip.name} has {chip.max_outputs}",
              f"node '{pops[-1].lif}'")


def rule_output_not_recurrent(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Output neurons have no recurrent connections."""
    if pops[-1].rec is not None:
        _fail(f"output neurons are not recurrent on {chip.name}; the readout population has the loop "
              f"'{pops[-1].rec}'", f"node '{pops[-1].lif}'")


def rule_input_expansion(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Input weights reach at most ``chip.max_input_expansion`` hidden neurons (IMU, Audio 3: 128)."""
    if len(pops) > 1:
        n = graph.node(pops[0].lif).n
        if n > chip.max_input_expansion:
            _fail(f"input expansion: the first hidden population '{pops[0].lif}' has {n} neurons fed by the "
                  f"inputs, {chip.name} lets inputs reach {chip.max_input_expansion}", f"node '{pops[0].lif}'")


def rule_output_expansion(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Output weights leave at most ``chip.max_output_expansion`` hidden neurons (IMU, Audio 3: 128)."""
    if len(pops) > 1:
        n = graph.node(pops[-2].lif).n
        if n > chip.max_output_expansion:
            _fail(f"output expansion: the last hidden population '{pops[-2].lif}' has {n} neurons feeding the "
                  f"outputs, {chip.name} lets {chip.max_output_expansion} feed them", f"node '{pops[-2].lif}'")


def rule_fanout(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """A hidden neuron reaches at most ``chip.max_fanout`` hidden neurons (its recurrent targets and the next
    hidden population's; Audio 2: 64). The spec check counts again, with what the lowering adds."""
    for k, p in enumerate(pops[:-1]):
        n = graph.node(p.lif).n
        fan = np.zeros(n, np.int64)
        if p.rec is not None:
            fan += np.count_nonzero(graph.node(p.rec).weight, axis=0)
        if k + 1 < len(pops) - 1:
            fan += np.count_nonzero(graph.node(pops[k + 1].ff).weight, axis=0)
        if fan.size and fan.max() > chip.max_fanout:
            j = int(np.argmax(fan))
            _fail(f"fan-out: neuron {j} of '{p.lif}' reaches {int(fan[j])} hidden neurons, {chip.name} allows "
                  f"{chip.max_fanout}", f"node '{p.lif}'")


def rule_delays(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Recurrent spikes arrive one step later on Xylo, and no delay is programmable: a recurrent IR delay
    must be 1 (feed-forward delays are absorbed by running populations late, ``timing.py``)."""
    for p in pops:
        if p.rec is not None:
            d = graph.delay(p.lif, p.rec) + graph.delay(p.rec, p.lif)
            if d != 1:
                _fail(f"delays: a recurrent projection with IR delay {d} steps; {chip.name} delivers recurrent "
                      "spikes exactly 1 step later", f"edge {p.lif}->{p.rec}->{p.lif}")


def rule_refractory(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Xylo neurons have no refractory period."""
    for p in pops:
        r = graph.node(p.lif).refractory
        if r > 1:
            _fail(f"refractory: {r} steps; {chip.name}'s neurons have none (1)", f"node '{p.lif}'.refractory")


def rule_one_dt(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """One time step for the whole network (Xylo has one clocked dt): the graph states it once, finite."""
    dts = {float(graph.dt)} if graph.dt is not None else set()
    for name, op in graph.items():
        stated = getattr(op, "dt", None)
        if stated is not None:
            dts.add(float(stated))
    if len(dts) != 1 or not all(math.isfinite(d) and d > 0 for d in dts):
        _fail(f"time step: Xylo runs one dt for every neuron; the graph states {sorted(dts) or 'none'}", "dt")


GRAPH_RULES: list[Callable[[Graph, list[Population], XyloChip], None]] = [
    rule_one_dt, rule_input_channels, rule_hidden_layers, rule_hidden_neurons, rule_output_neurons,
    rule_output_not_recurrent, rule_input_expansion, rule_output_expansion, rule_fanout, rule_delays,
    rule_refractory,
]


def check_graph(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    for rule in GRAPH_RULES:
        rule(graph, pops, chip)


# -- on a spec -------------------------------------------------------------------------------------

def check_spec(spec: dict, chip: XyloChip) -> None:
    """A spec dict as ``XyloSpec`` (its own consistency checks: dtypes, shapes, the core's ranges) within
    ``chip``'s limits (``XyloSpec.chip_violations``: sizes, expansion neurons, synapses, fan-out, aliases);
    the first broken rule as one ``SnnccError`` line."""
    from snncc.targets.xylo.spec import XyloSpec

    XyloSpec(**spec).check_chip(chip)
