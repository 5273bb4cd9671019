"""Xylo design rules: small functions, each refusing in one line that names the rule and the numbers.

``GRAPH_RULES`` run on the IR chain before lowering (``check_graph``), ``SPEC_RULES`` on a spec dict
(``check_spec``: a spec snncc wrote, or one a user brings). The real-time check (``cycles_per_step``,
``real_time``) estimates the core's clock cycles per time step and compares them with ``dt``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import Input
from snncc.targets.xylo.chip_table import SAFE_WEIGHT_SHIFT, XyloChip
from snncc.targets.xylo.structure import Population


def _fail(rule: str, field: str) -> None:
    raise SnnccError(rule, field=field)


# -- on the IR chain ------------------------------------------------------------------------------

def rule_input_channels(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """At most ``chip.inputs`` input channels."""
    width = graph.node(pops[0].pre).width
    if width > chip.inputs:
        _fail(f"input channels: the model has {width}, {chip.name} has {chip.inputs}", f"node '{pops[0].pre}'")


def rule_hidden_layers(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Inputs reach output neurons only through hidden neurons: at least one hidden population."""
    if len(pops) < 2:
        _fail(f"hidden neurons: the model's inputs feed its readout population '{pops[-1].lif}' directly; "
              f"{chip.name}'s inputs reach output neurons only through hidden neurons", "graph")


def rule_hidden_neurons(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """The hidden populations together fit the hidden neurons."""
    n = sum(graph.node(p.lif).n for p in pops[:-1])
    if n > chip.hidden:
        _fail(f"hidden neurons: the model needs {n} ({', '.join(f'{p.lif} {graph.node(p.lif).n}' for p in pops[:-1])}), "
              f"{chip.name} has {chip.hidden}", "graph")


def rule_output_neurons(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """The readout population fits the output neurons."""
    n = graph.node(pops[-1].lif).n
    if n > chip.outputs:
        _fail(f"output neurons: the readout population has {n}, {chip.name} has {chip.outputs}", f"node '{pops[-1].lif}'")


def rule_output_not_recurrent(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Output neurons have no recurrent connections."""
    if pops[-1].rec is not None:
        _fail(f"output neurons are not recurrent on {chip.name}; the readout population has the loop "
              f"'{pops[-1].rec}'", f"node '{pops[-1].lif}'")


def rule_input_expansion(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Input weights reach at most ``chip.input_expansion`` hidden neurons (IMU, Audio 3: 128)."""
    if chip.input_expansion is not None and len(pops) > 1:
        n = graph.node(pops[0].lif).n
        if n > chip.input_expansion:
            _fail(f"input expansion: the first hidden population '{pops[0].lif}' has {n} neurons fed by the "
                  f"inputs, {chip.name} lets inputs reach {chip.input_expansion}", f"node '{pops[0].lif}'")


def rule_output_expansion(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    """Output weights leave at most ``chip.output_expansion`` hidden neurons (IMU, Audio 3: 128)."""
    if chip.output_expansion is not None and len(pops) > 1:
        n = graph.node(pops[-2].lif).n
        if n > chip.output_expansion:
            _fail(f"output expansion: the last hidden population '{pops[-2].lif}' has {n} neurons feeding the "
                  f"outputs, {chip.name} lets {chip.output_expansion} feed them", f"node '{pops[-2].lif}'")


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
    rule_output_not_recurrent, rule_input_expansion, rule_output_expansion, rule_delays, rule_refractory,
]


def check_graph(graph: Graph, pops: list[Population], chip: XyloChip) -> None:
    for rule in GRAPH_RULES:
        rule(graph, pops, chip)


# -- on a spec dict ---------------------------------------------------------------------------------

def _arr(spec: dict, key: str) -> np.ndarray:
    if key not in spec:
        _fail("missing from the spec", key)
    return np.asarray(spec[key])


def rule_spec_sizes(spec: dict, chip: XyloChip) -> None:
    """Inputs, hidden and output neurons within the chip; shapes agree with each other."""
    w_in, w_rec, w_out = _arr(spec, "weights_in"), _arr(spec, "weights_rec"), _arr(spec, "weights_out")
    n = _arr(spec, "threshold").size
    n_out = _arr(spec, "threshold_out").size
    for what, got, cap, key in (("input channels", w_in.shape[0], chip.inputs, "weights_in"),
                                ("hidden neurons", n, chip.hidden, "threshold"),
                                ("output neurons", n_out, chip.outputs, "threshold_out")):
        if got > cap:
            _fail(f"{what}: the spec has {got}, {chip.name} has {cap}", key)
    if w_in.ndim not in (2, 3) or w_in.shape[1] > n:
        _fail(f"must be (Nin, N_ien <= {n}[, 2]), got {w_in.shape}", "weights_in")
    if w_rec.shape[:2] != (n, n):
        _fail(f"must be ({n}, {n}[, 2]), got {w_rec.shape}", "weights_rec")
    if w_out.ndim != 2 or w_out.shape[1] != n_out or w_out.shape[0] > n:
        _fail(f"must be (N_oen <= {n}, {n_out}), got {w_out.shape}", "weights_out")
    for key, size in (("dash_mem", n), ("dash_syn", n), ("dash_syn_2", n), ("bias", n),
                      ("dash_mem_out", n_out), ("dash_syn_out", n_out), ("bias_out", n_out)):
        if key in spec and np.asarray(spec[key]).size != size:
            _fail(f"must have {size} values, got {np.asarray(spec[key]).size}", key)


def rule_spec_ranges(spec: dict, chip: XyloChip) -> None:
    """int8 weights, 4-bit dashes, int16 thresholds (> 0) and biases, shifts 0..8 (no weight wraps)."""
    for key in ("weights_in", "weights_rec", "weights_out"):
        w = _arr(spec, key)
        if w.size and (w.min() < -128 or w.max() > 127 or not np.all(np.equal(np.mod(w, 1), 0))):
            _fail(f"weights must be int8, got values in [{w.min()}, {w.max()}]", key)
    for key in ("dash_mem", "dash_syn", "dash_syn_2", "dash_mem_out", "dash_syn_out"):
        if key in spec:
            d = np.asarray(spec[key])
            if d.size and (d.min() < 0 or d.max() > chip.dash_max):
                _fail(f"dashes are 4-bit (0..{chip.dash_max}), got [{d.min()}, {d.max()}]", key)
    for key in ("threshold", "threshold_out"):
        t = _arr(spec, key)
        if t.size and (t.min() < 1 or t.max() > 2 ** 15 - 1):
            _fail(f"thresholds are int16 and > 0, got [{t.min()}, {t.max()}]", key)
    for key in ("bias", "bias_out"):
        if key in spec:
            b = np.asarray(spec[key])
            if b.size and (b.min() < -(2 ** 15) or b.max() > 2 ** 15 - 1):
                _fail(f"biases are int16, got [{b.min()}, {b.max()}]", key)
    for key in ("weight_shift_in", "weight_shift_rec", "weight_shift_out"):
        s = int(spec.get(key, 0))
        if not 0 <= s <= SAFE_WEIGHT_SHIFT:
            _fail(f"weight shift {s}: 0..{SAFE_WEIGHT_SHIFT} (larger shifts wrap int8 weights in int16)", key)


def rule_spec_synapses(spec: dict, chip: XyloChip) -> None:
    """A second synapse per hidden neuron only where the chip has one (Audio 2, Audio 3; not IMU)."""
    if chip.synapses >= 2:
        return
    for key in ("weights_in", "weights_rec"):
        w = _arr(spec, key)
        if w.ndim == 3 and w.shape[2] > 1 and np.any(w[:, :, 1:]):
            _fail(f"synapses per neuron: the spec uses a second synaptic current, {chip.name} has {chip.synapses}",
                  key)


def rule_spec_expansion(spec: dict, chip: XyloChip) -> None:
    """Input weights only to the first ``input_expansion`` and output weights only from the last
    ``output_expansion`` hidden neurons (IMU, Audio 3: 128 each)."""
    n = _arr(spec, "threshold").size
    if chip.input_expansion is not None:
        w_in = _arr(spec, "weights_in")
        cols = np.flatnonzero(np.any(w_in.reshape(w_in.shape[0], w_in.shape[1], -1) != 0, axis=(0, 2)))
        if cols.size and cols.max() >= chip.input_expansion:
            _fail(f"input expansion: input weights reach hidden neuron {cols.max()}, {chip.name} lets them reach the "
                  f"first {chip.input_expansion}", "weights_in")
    if chip.output_expansion is not None:
        w_out = _arr(spec, "weights_out")
        rows = np.flatnonzero(np.any(w_out != 0, axis=1)) + (n - w_out.shape[0])
        if rows.size and rows.min() < n - chip.output_expansion:
            _fail(f"output expansion: output weights leave hidden neuron {rows.min()}, {chip.name} lets the last "
                  f"{chip.output_expansion} (from {n - chip.output_expansion}) feed them", "weights_out")


def rule_spec_aliases(spec: dict, chip: XyloChip) -> None:
    """Aliases name hidden neurons."""
    n = _arr(spec, "threshold").size
    aliases = spec.get("aliases") or []
    if aliases and len(aliases) != n:
        _fail(f"must hold one list per hidden neuron ({n}), got {len(aliases)}", "aliases")
    for j, targets in enumerate(aliases):
        for t in targets:
            if not 0 <= int(t) < n:
                _fail(f"neuron {j}'s alias {t} is not a hidden neuron (0..{n - 1})", "aliases")


SPEC_RULES: list[Callable[[dict, XyloChip], None]] = [
    rule_spec_sizes, rule_spec_ranges, rule_spec_synapses, rule_spec_expansion, rule_spec_aliases,
]


def check_spec(spec: dict, chip: XyloChip) -> None:
    for rule in SPEC_RULES:
        rule(spec, chip)


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
    w_in = np.asarray(spec["weights_in"])
    w_rec = np.asarray(spec["weights_rec"])
    n_in, n_ien = w_in.shape[:2]
    n = w_rec.shape[0]
    n_out = np.asarray(spec["weights_out"]).shape[1]
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
