"""The teacher: the float graph as trained (its own reset), run by the IR reference simulator.

Per population it records spikes and, for losses on the membrane, the voltage BEFORE reset divided
by the threshold: V_pre[t] = beta * V[t-1] + I[t] (+ voltage bias), 0 while refractory (the
simulator records V after reset; for reset "subtract" V_pre = V + theta * s).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF

TEACHER_BATCH = 256


@dataclass
class TeacherRun:
    counts: np.ndarray                                          # (N, n_out) output spike counts
    spikes: dict[str, np.ndarray] = field(default_factory=dict)  # population -> (N, T, n) uint8
    voltage: dict[str, np.ndarray] = field(default_factory=dict)  # population -> (N, T, n) float32 V_pre / theta

    def select(self, index: np.ndarray) -> "TeacherRun":
        return TeacherRun(self.counts[index], {k: v[index] for k, v in self.spikes.items()},
                          {k: v[index] for k, v in self.voltage.items()})


def _pre_reset(op: LIF, dt: float, spikes: np.ndarray, current: np.ndarray, voltage: np.ndarray) -> np.ndarray:
    """V before reset from the simulator's records ((B, T, n) arrays)."""
    _, beta = op.decays(dt)
    beta = np.asarray(beta, dtype=voltage.dtype)
    prev = np.concatenate([np.zeros_like(voltage[:, :1]), voltage[:, :-1]], axis=1)
    pre = beta * prev + current
    if op.bias is not None and op.bias_placement == "voltage":
        pre = pre + np.asarray(op.bias, dtype=voltage.dtype)
    if op.refractory > 1:   # held at 0 for refractory - 1 steps after a spike
        held = np.zeros(spikes.shape, dtype=bool)
        for k in range(1, op.refractory):
            held[:, k:] |= spikes[:, :-k] > 0
        pre = np.where(held, 0.0, pre)
    return pre


def run_teacher(graph: Graph, x: np.ndarray, populations: tuple[str, ...], *, voltage: bool = True,
                batch: int = TEACHER_BATCH, progress=None) -> TeacherRun:
    """Spikes (and V_pre / theta) of every population of ``graph`` on inputs (N, T, C), in batches."""
    from snncc.ir.simulate import simulate

    spikes = {p: [] for p in populations}
    volts = {p: [] for p in populations}
    for start in range(0, x.shape[0], batch):
        res = simulate(graph, x[start:start + batch], record="all" if voltage else "spikes")
        for p in populations:
            s = res.spikes[p]
            spikes[p].append(np.asarray(s).astype(np.uint8))
            if voltage:
                op = graph.node(p)
                pre = _pre_reset(op, graph.dt, s, res.current[p], res.voltage[p])
                theta = np.asarray(op.threshold, dtype=pre.dtype)
                volts[p].append((pre / theta).astype(np.float32))
        if progress is not None:
            progress(min(start + batch, x.shape[0]))
    out = TeacherRun(counts=np.zeros((x.shape[0], 0)))
    out.spikes = {p: np.concatenate(v) for p, v in spikes.items()}
    if voltage:
        out.voltage = {p: np.concatenate(v) for p, v in volts.items()}
    out.counts = out.spikes[populations[-1]].sum(axis=1, dtype=np.int64)
    return out
