"""Timing lowering for Loihi 1: IR edge delays and refractory periods -> synaptic delays and refDelay.

On Loihi every edge delivers a spike one step after it is sent, plus an optional synaptic delay
(0..62 steps, ``chip.MAX_EXTRA_DELAY``). A projection pre -> Dense -> post with IR total delay d
therefore lowers to an extra delay d - 1; the IR refractory period r lowers to refDelay = r
(1..63, ``chip.REF_DELAY_MAX``).

    timing="exact": keep the IR's order. A projection with d = 0 cannot be exact step for step;
        the pass then delays whole populations (spike trains identical, shifted by s_P steps):
        Loihi delay of pre -> post = d + s_post - s_pre >= 1 (a difference-constraint system, solved
        by longest paths; infeasible only when a cycle has fewer delay steps than projections).
        tSample grows by the output's shift, so spike counts over the sample are unchanged.
        A population whose current has a bias from IR step k on needs s_post + k >= 1 too: the
        always-on source that carries the bias on Loihi delivers one step after it fires.
        A voltage bias (NIR v_leak) sits in the compartment and acts from the chip's first step, so
        on a population delayed by s >= 1 it would charge V for s steps before the population's
        IR step 0. Where the population has no synaptic memory (alpha = 0 for every biased neuron;
        NIR's LIF), I[t] = in[t] + b gives V[t] = beta*V[t-1] + in[t] + b, the same V and spikes, so
        the bias moves onto the current and an always-on source delivers it from IR step 0 on.
        With alpha != 0 no constant current term reproduces it, and the graph is refused.
    timing="paper": the authors' export: every projection delay 1 (no synaptic delay), refDelay 1.
        This changes the update order the model was trained in; ``snncc check`` measures the cost.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input
from snncc.targets.kit.graphs import current_biases
from snncc.targets.loihi import chip
from snncc.targets.loihi.options import TIMINGS


@dataclass
class ProjectionTiming:
    pre: str
    dense: str
    post: str
    ir_delay: int        # total IR delay pre -> dense -> post
    loihi_delay: int     # total steps on Loihi (>= 1): 1 (delivery) + extra
    extra_delay: int     # the synaptic delay programmed (0..chip.MAX_EXTRA_DELAY)


@dataclass
class TimingRecord:
    mode: str
    projections: list[ProjectionTiming] = field(default_factory=list)
    ref_delay: dict[str, int] = field(default_factory=dict)
    shifts: dict[str, int] = field(default_factory=dict)   # population -> steps its spike train is delayed
    output_shift: int = 0
    changes: list[str] = field(default_factory=list)         # what differs from the IR as given

    @property
    def exact(self) -> bool:
        return self.mode == "exact"

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def projection_paths(graph: Graph) -> list[tuple[str, str, str]]:
    """(pre, dense, post) for every population -> Dense -> LIF path (pre is an Input or a LIF)."""
    paths = []
    for dense, op in graph.items():
        if not isinstance(op, Dense):
            continue
        preds = graph.predecessors(dense)
        for post in graph.successors(dense):
            if not isinstance(graph.node(post), LIF):
                raise SnnccError("on Loihi a Dense must feed a LIF population", field=f"edge {dense}->{post}")
            for pre in preds:
                if not isinstance(graph.node(pre), (Input, LIF)):
                    raise SnnccError("on Loihi a Dense must be fed by the input or a LIF population",
                                     field=f"edge {pre}->{dense}")
                if graph.port(pre, dense) != "spikes":
                    raise SnnccError("Loihi sends spikes between cores, not voltages", field=f"edge {pre}->{dense}")
                paths.append((pre, dense, post))
    return paths


def total_delay(graph: Graph, pre: str, dense: str, post: str) -> int:
    return graph.delay(pre, dense) + graph.delay(dense, post)


def paper_order(graph: Graph) -> tuple[Graph, list[str]]:
    """The authors' export as an IR graph: every projection delay 1, every refractory period 1."""
    g = graph.copy()
    changes: list[str] = []
    for pre, dense, post in projection_paths(graph):
        d = total_delay(graph, pre, dense, post)
        if d != 1:
            changes.append(f"{pre}->{post}: delay {d} -> 1")
        g.set_delay(pre, dense, 1)
        g.set_delay(dense, post, 0)
    for name, op in g.items():
        if isinstance(op, LIF) and op.refractory != 1:
            changes.append(f"{name}: refractory {op.refractory} -> 1")
            op.refractory = 1
    return g, changes


def bias_shift(graph: Graph, lif: str) -> int:
    """Smallest shift letting an always-on source reach ``lif`` from its first biased step: 1 - k."""
    starts = [t.start for t in current_biases(graph, lif)]
    return max(0, 1 - min(starts)) if starts else 0


def _solve_shifts(graph: Graph, paths: list[tuple[str, str, str]]) -> dict[str, int]:
    """Smallest s >= 0 per population with d + s_post - s_pre >= 1 on every projection (s_input = 0)
    and s >= ``bias_shift`` for populations with current biases."""
    pops = [n for n, op in graph.items() if isinstance(op, (Input, LIF))]
    shift = {p: bias_shift(graph, p) if isinstance(graph.node(p), LIF) else 0 for p in pops}
    for _ in range(len(pops) + 1):
        changed = False
        for pre, dense, post in paths:
            need = shift[pre] + 1 - total_delay(graph, pre, dense, post)
            if need > shift[post]:
                if isinstance(graph.node(post), Input):
                    continue
                shift[post] = need
                changed = True
        if not changed:
            return shift
    raise SnnccError("a cycle has fewer delay steps than projections, so it cannot run on Loihi (every "
                     "projection there takes at least one step)", field="delays")


def _late_voltage_biases(graph: Graph, shift: dict[str, int]) -> list[str]:
    """Populations delayed by the timing pass that carry a non-zero voltage bias (see the module docstring)."""
    late = []
    for name, op in graph.items():
        if isinstance(op, LIF) and shift.get(name, 0) > 0 and op.bias is not None and op.bias_placement == "voltage" \
                and np.any(op.bias != 0):
            alpha, _ = op.decays(graph.dt)
            if np.any(alpha[op.bias != 0] != 0):
                raise SnnccError(
                    f"a voltage bias (NIR v_leak) cannot start on time on Loihi 1 here: the population runs "
                    f"{shift[name]} step(s) late (every edge there delivers one step later), a compartment bias acts "
                    "from the chip's first step, and with a synaptic current (tau_syn > dt) it has no exact form on "
                    "the current", field=f"node '{name}'.bias")
            late.append(name)
    return late


def lower_timing(graph: Graph, mode: str = "exact") -> tuple[Graph, TimingRecord]:
    """Return (graph in the order Loihi will run, record of delays, refDelay and shifts).

    In exact mode the graph is returned itself unless a voltage bias had to move onto the current."""
    if mode not in TIMINGS:
        raise SnnccError(f"timing must be one of {TIMINGS}", field="--timing")
    record = TimingRecord(mode=mode)
    if mode == "paper":
        g, record.changes = paper_order(graph)
    else:
        g = graph
    paths = projection_paths(g)
    shift = _solve_shifts(g, paths)
    late = _late_voltage_biases(g, shift)
    if late:
        g = g.copy() if g is graph else g
        for name in late:
            g.node(name).bias_placement = "current"
            record.changes.append(
                f"{name}: its voltage bias is carried on the current by an always-on source (the population runs "
                f"{shift[name]} step(s) late on Loihi and a compartment bias would act before its first step; exact: "
                "it has no synaptic memory, alpha = 0)")
    record.shifts = {p: s for p, s in shift.items() if s}
    for pre, dense, post in paths:
        d = total_delay(g, pre, dense, post)
        loihi = d + shift[post] - shift[pre]
        extra = loihi - 1
        if extra > chip.MAX_EXTRA_DELAY:
            raise SnnccError(f"needs a synaptic delay of {extra} steps; Loihi allows at most {chip.MAX_EXTRA_DELAY}",
                             field=f"edge {pre}->{dense}->{post}")
        record.projections.append(ProjectionTiming(pre, dense, post, d, loihi, extra))
    for name, op in g.items():
        if isinstance(op, LIF):
            if not chip.REF_DELAY_MIN <= op.refractory <= chip.REF_DELAY_MAX:
                raise SnnccError(f"a refractory period of {op.refractory} steps does not fit Loihi's refDelay "
                                 f"({chip.REF_DELAY_MIN}..{chip.REF_DELAY_MAX})", field=f"node '{name}'.refractory")
            record.ref_delay[name] = int(op.refractory)
    outs = [n for n, op in g.items() if isinstance(op, LIF) and not any(
        isinstance(g.node(s), Dense) for s in g.successors(n))]
    record.output_shift = max((shift[o] for o in outs), default=0)
    if record.shifts:
        biased = [p for p in record.shifts if bias_shift(g, p)]
        reasons = (["projection(s) with IR delay 0"] if any(p.ir_delay == 0 for p in record.projections) else []) + (
            [f"current biases of {biased} (carried by always-on sources)"] if biased else [])
        why = " and ".join(reasons)
        record.changes.append(
            f"{why} cannot be exact step for step on Loihi without a shift (every edge delivers one step "
            f"later): populations delayed by {record.shifts} steps; spike trains are identical but shifted, and "
            f"tSample grows by {record.output_shift} so counts over the sample are unchanged")
    return g, record
