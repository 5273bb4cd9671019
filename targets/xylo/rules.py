"""Xylo design rules: small functions, each refusing in one line that names the rule and the numbers.

``GRAPH_RULES`` run on the IR chain before lowering (``check_graph``); a spec is checked by
``XyloSpec`` and its chip limits (``check_spec``). The real-time check (``cycles_per_step``,
``real_time``) estimates the core's clock cycles per time step and compares them with ``dt``.
Chip limits come from ``chip.py`` (``XyloChip``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import Input
from snncc.targets.xylo.chip import XyloChip
from snncc.targets.xylo.structure import Population


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


# -- real time ----------------------------------------------------------------------------------------

# Cycle costs of the Audio 2 core per operation, as published by SynSense in Rockpool 3.1's Audio 2 cycles
# model (syns61201/power_cycles_model.py); the model below is snncc's own: an ESTIMATE, not a measurement.
CYCLES_INPUT_EVENT_PER_NEURON = 3.5   # an input event scans the input-expansion neurons' weights
CYCLES_INPUT_CHANNEL = 1
CYCLES_HIDDEN_SYNAPSE_EVENT = 7       # a hidden spike, per recurrent synapse it reaches
CYCLES_HIDDEN_NEURON_ISYN = 3
CYCLES_OUTPUT_SYNAPSE_EVENT = 8       # a hidden spike, per output neuron
CYCLES_OUTPUT_SCAN = 1
CYCLES_HIDDEN_NEURON = 19             # each hidden neuron's update
CYCLES_HIDDEN_SPIKE = 3               # extra work of a spiking hidden neuron
CYCLES_OUTPUT_NEURON = 12
CORE_CLOCK_MAX_HZ = 50e6              # the Audio 2 HDK's core clock: 100 MHz / 2 at the fastest setting


@dataclass
class RealTime:
    cycles_worst: float          # every input channel, hidden and output neuron active every step
    cycles_expected: float       # at the given (or measured) event rates
    clock_hz: float
    dt: float
    rates: dict[str, float]

    @property
    def step_time_worst(self) -> float:
        return self.cycles_worst / self.clock_hz

    @property
    def real_time(self) -> bool:
        return self.step_time_worst <= self.dt

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(step_time_worst_s=self.step_time_worst, real_time=self.real_time,
                 margin=self.dt / self.step_time_worst if self.step_time_worst else math.inf,
                 margin_expected=(self.dt * self.clock_hz / self.cycles_expected if self.cycles_expected
                                  else math.inf),
                 note="ESTIMATE from per-operation cycle costs (SynSense, Rockpool 3.1 Audio 2 model); not measured")
        return d

    def line(self) -> str:
        verdict = "runs in real time" if self.real_time else "does NOT run in real time"
        return (f"{verdict}: at most {self.cycles_worst:,.0f} core cycles per step ({self.step_time_worst * 1e6:.1f} us "
                f"at {self.clock_hz / 1e6:g} MHz) against dt = {self.dt * 1e6:g} us; {self.cycles_expected:,.0f} "
                "cycles expected at the measured event rates (ESTIMATE)")


def cycles_per_step(spec: dict, input_rate: float = 1.0, hidden_rate: float = 1.0, output_rate: float = 1.0) -> float:
    """Core cycles one step needs: input events scan the input-expansion neurons, each hidden spike its
    recurrent fan-out and the output neurons, then every hidden and output neuron updates. Rates are the
    probabilities that a channel / neuron has an event in a step (1: worst case)."""
    get = spec.__getitem__ if isinstance(spec, dict) else lambda k: getattr(spec, k)   # a dict or an XyloSpec
    w_in = np.asarray(get("weights_in"))
    w_rec = np.asarray(get("weights_rec"))
    w_rec = w_rec if w_rec.ndim == 3 else w_rec[:, :, None]
    n_in, n_ien = w_in.shape[:2]
    n = w_rec.shape[0]
    n_out = np.asarray(get("weights_out")).shape[1]
    fanout = float(np.mean(np.count_nonzero(w_rec.reshape(n, n, -1).any(axis=2), axis=1))) if n else 0.0
    inputs = n_in * (input_rate * n_ien * CYCLES_INPUT_EVENT_PER_NEURON + CYCLES_INPUT_CHANNEL)
    recurrent = n * (hidden_rate * fanout * CYCLES_HIDDEN_SYNAPSE_EVENT + CYCLES_HIDDEN_NEURON_ISYN)
    to_output = n * hidden_rate * (CYCLES_OUTPUT_SCAN + n_out * CYCLES_OUTPUT_SYNAPSE_EVENT)
    neurons = n * (CYCLES_HIDDEN_NEURON + hidden_rate * CYCLES_HIDDEN_SPIKE) + n_out * CYCLES_OUTPUT_NEURON
    return float(inputs + recurrent + to_output + neurons)


def real_time(spec: dict, dt: float, rates: dict[str, float] | None = None,
              clock_hz: float = CORE_CLOCK_MAX_HZ) -> RealTime:
    """Worst-case and expected cycles per step against ``dt`` at ``clock_hz``."""
    r = {"input": 1.0, "hidden": 1.0, "output": 1.0, **(rates or {})}
    return RealTime(cycles_per_step(spec), cycles_per_step(spec, r["input"], r["hidden"], r["output"]),
                    float(clock_hz), float(dt), r)
