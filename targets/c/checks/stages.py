"""The float graphs between the model and the C artefact, each one cause of loss further (``kit.checks``):

    weights    the model's graph with the artefact's weights, thresholds and biases read back in float (each
               projection one Dense from its source, at its delay; each current-bias term a bias arriving from
               its start step), float decays and state                                    cause "weights"
    decays     the same with the artefact's Q16 decays (time constants read back from them)  cause "decays"

Built from the artefact's own network (``network.npz``), never re-derived from the model, so what they measure
is what was written. The integer stages (state on the grid without saturation, then the artefact itself) run
in the emulator (``checks/agreement.py``).
"""

from __future__ import annotations

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.targets.c.lowering.quantize import float_reading, float_weights

HUGE_TAU = 1e30            # a decay of exactly 1 (a perfect integrator) as a time constant


def _tau(factor: np.ndarray, dt: float, discretisation: str) -> np.ndarray:
    f = np.asarray(factor, np.float64)
    if discretisation == "euler":
        with np.errstate(divide="ignore"):
            return np.where(f >= 1.0, HUGE_TAU, dt / np.maximum(1.0 - f, 1e-300))
    with np.errstate(divide="ignore"):
        return np.where(f >= 1.0, HUGE_TAU, -dt / np.log(np.clip(f, 1e-300, 1.0)))


def stage_graph(graph: Graph, net, *, decays: bool) -> Graph:   # noqa: ANN001 (a CNetwork)
    """The float graph of ``net`` (module doc); ``decays``: with the artefact's decays, else the model's."""
    g = Graph(dt=graph.dt, name=f"{graph.name}-c-{'decays' if decays else 'weights'}", metadata=dict(graph.metadata))
    inp = net.names.get("input") or "input"
    g.add(inp, Input(width=net.inputs))
    for i, pop in enumerate(net.populations):
        op: LIF = graph.node(pop.name)
        read = float_reading(net, i)
        unit = 2.0 ** -pop.frac_bits
        tau_syn, tau_mem = op.tau_syn, op.tau_mem
        if decays:
            tau_syn = _tau(read["alpha"], graph.dt, op.discretisation)
            tau_mem = _tau(read["beta"], graph.dt, op.discretisation)
        g.add(pop.name, LIF(n=pop.n, tau_syn=tau_syn, tau_mem=tau_mem, threshold=read["threshold"], reset=op.reset,
                            refractory=op.refractory, discretisation=op.discretisation,
                            bias=None if pop.bias_v is None else pop.bias_v * unit, bias_placement="voltage",
                            max_spikes=op.max_spikes, fire_test=op.fire_test))
    for k, q in enumerate(net.projections):
        name = f"c.w{k}"
        g.add(name, Dense(weight=float_weights(net, q)))
        g.connect(inp if q.source < 0 else net.populations[q.source].name, name, delay=q.delay)
        g.connect(name, net.populations[q.target].name, delay=0)
    for i, pop in enumerate(net.populations):
        unit = 2.0 ** -pop.frac_bits
        for t, term in enumerate(pop.bias_i):
            name = f"c.b{i}_{t}"
            g.add(name, Dense(weight=np.zeros((pop.n, net.inputs)), bias=term.values * unit))
            g.connect(inp, name, delay=0)
            g.connect(name, pop.name, delay=int(term.start))
    out = net.populations[net.output].name
    g.add("c.readout", Readout(width=net.outputs))
    g.connect(out, "c.readout")
    g.add("c.output", Output(width=net.outputs))
    g.connect("c.readout", "c.output")
    return g


__all__ = ["stage_graph"]
