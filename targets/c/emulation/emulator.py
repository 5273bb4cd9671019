"""The bit-exact emulator of a C artefact: the arithmetic of ``snn.c``, stated once more in numpy, batched.

One step t (``snn_step``), populations in the network's order, for each neuron j of population p:

    syn    = sum over projections k into p of  acc_k[j] * 2**e_k[j],
             acc_k[j] = sum over events (i, c) of k's source at step t - d_k of  c * w_k[i, j]
    I      = sat32( rnd16(alpha[j] * I) + syn + sum of current-bias terms with start <= t )
    V      = sat32( rnd16(beta[j] * V) + I + bias_v[j] )
    if ref[j] > 0:  V = 0, ref[j] -= 1
    s      = 0; while s < max_spikes and V (> | >=) theta[j]:  V -= theta[j], s += 1
    if s > 0 and reset is zero: V = 0;  if s > 0 and refractory > 1: ref[j] = refractory - 1

    rnd16(x) = floor((x + 2**15) / 2**16)   (round half up; numpy's >> on int64 is that floor)
    sat32(x) = min(max(x, -2**31), 2**31 - 1), x computed exactly (int64; |syn| < 2**52 by construction)

An event list of a source is the set of its neurons that spiked at a step (with their counts): the event-driven
delivery of the C equals a matrix product of the spike counts with the weights, which is what runs here (in
float64, exact: every partial sum is an integer below 2**53). ``saturate=False`` runs the same arithmetic with
unbounded state (the checks' stage that isolates saturation).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from snncc.targets.c.lowering.network import CNetwork
from snncc.targets.c.options import DECAY_BITS

INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1
HALF = 1 << (DECAY_BITS - 1)


@dataclass
class EmulatorRun:
    """What one run produced: output spikes (B, T, N) uint8, counts (B, N) int64 and, recorded, per population
    spikes (B, T, n) uint8, current and voltage (after reset) (B, T, n) int64; saturation events per population."""

    output_spikes: np.ndarray
    counts: np.ndarray
    spikes: dict[str, np.ndarray] = field(default_factory=dict)
    current: dict[str, np.ndarray] = field(default_factory=dict)
    voltage: dict[str, np.ndarray] = field(default_factory=dict)
    saturated: dict[str, int] = field(default_factory=dict)


def rnd16(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """floor((a * x + 2**15) / 2**16) for int64 arrays (the C's ``decay``)."""
    return (a * x + HALF) >> DECAY_BITS


def _weights(net: CNetwork):
    """Per projection, the fan-out matrix as the product takes it (dense float64, or scipy CSR) and 2**e."""
    import scipy.sparse as sp

    out = []
    for q in net.projections:
        w = q.weights.astype(np.float64)
        mat = sp.csr_matrix(w) if q.layout == "sparse" else w
        out.append((q, mat, np.left_shift(np.int64(1), q.exponent.astype(np.int64))))
    return out


SPARSE_EVENTS = 0.1       # below this share of spiking sources, events are gathered as a sparse matrix


def _deliver(s: np.ndarray, mat) -> np.ndarray:   # noqa: ANN001 (ndarray or scipy CSR)
    """The events ``s`` (B, n_src) times the fan-out rows ``mat`` (n_src, n_tgt): exact in float64 (integers below
    2**53), the work proportional to the events where they are few."""
    import scipy.sparse as sp

    if np.count_nonzero(s) < SPARSE_EVENTS * s.size:
        out = sp.csr_matrix(s) @ mat
        return out.toarray() if sp.issparse(out) else np.asarray(out)
    if isinstance(mat, np.ndarray):
        return s @ mat
    return np.asarray((mat.T @ s.T).T)


def emulate_network(net: CNetwork, x: np.ndarray, *, record: bool = False, saturate: bool = True,
                    populations: tuple[str, ...] = (), progress: Callable[[int], None] | None = None) -> EmulatorRun:
    """Run ``net`` on ``x`` (B, T, inputs) 0/1 from reset. ``record``: every population's spikes, current and
    voltage; ``populations``: record only these populations' spikes (for checks)."""
    x = np.asarray(x)
    batch, steps = int(x.shape[0]), int(x.shape[1])
    weights = _weights(net)
    pops = net.populations
    slots = {s: net.max_delay(s) + 1 for s in range(-1, len(pops))}
    hist: dict[int, list[np.ndarray | None]] = {s: [None] * slots[s] for s in slots}
    cur = [np.zeros((batch, p.n), np.int64) for p in pops]
    vol = [np.zeros((batch, p.n), np.int64) for p in pops]
    ref = [np.zeros((batch, p.n), np.int64) for p in pops]
    out = np.zeros((batch, steps, net.outputs), np.uint8)
    saturated = {p.name: 0 for p in pops}
    keep = {p.name for p in pops} if record else set(populations)
    rec_s = {p.name: np.zeros((batch, steps, p.n), np.uint8) for p in pops if p.name in keep}
    rec_i = {p.name: np.zeros((batch, steps, p.n), np.int64) for p in pops} if record else {}
    rec_v = {p.name: np.zeros((batch, steps, p.n), np.int64) for p in pops} if record else {}

    def clamp(a: np.ndarray, name: str) -> np.ndarray:
        if not saturate:
            return a
        hit = (a < INT32_MIN) | (a > INT32_MAX)
        if hit.any():
            saturated[name] += int(np.count_nonzero(hit))
            return np.clip(a, INT32_MIN, INT32_MAX)
        return a

    for t in range(steps):
        xs = x[:, t].astype(np.float64)
        hist[-1][t % slots[-1]] = xs if xs.any() else None
        for p, pop in enumerate(pops):
            syn = np.zeros((batch, pop.n), np.int64)
            for q, mat, scale in weights:
                if q.target != p or t < q.delay:
                    continue
                s = hist[q.source][(t - q.delay) % slots[q.source]]
                if s is None:
                    continue
                syn += _deliver(s, mat).astype(np.int64) * scale
            i_new = rnd16(pop.alpha, cur[p]) + syn
            for term in pop.bias_i:
                if t >= term.start:
                    i_new = i_new + term.values
            i_new = clamp(i_new, pop.name)
            v_new = rnd16(pop.beta, vol[p]) + i_new
            if pop.bias_v is not None:
                v_new = v_new + pop.bias_v
            v_new = clamp(v_new, pop.name)
            held = ref[p] > 0
            if held.any():
                v_new = np.where(held, 0, v_new)
                ref[p] = np.where(held, ref[p] - 1, ref[p])
            spikes = np.zeros((batch, pop.n), np.int64)
            if pop.fires:
                for _ in range(pop.max_spikes):
                    test = v_new > pop.threshold if pop.fire_test == ">" else v_new >= pop.threshold
                    if not test.any():
                        break
                    v_new = np.where(test, v_new - pop.threshold, v_new)
                    spikes += test
                fired = spikes > 0
                if pop.reset == "zero":
                    v_new = np.where(fired, 0, v_new)
                if pop.refractory > 1:
                    ref[p] = np.where(fired, pop.refractory - 1, ref[p])
            cur[p], vol[p] = i_new, v_new
            hist[p][t % slots[p]] = spikes.astype(np.float64) if spikes.any() else None
            if p == net.output:
                out[:, t] = spikes
            if pop.name in rec_s:
                rec_s[pop.name][:, t] = spikes
            if record:
                rec_i[pop.name][:, t] = i_new
                rec_v[pop.name][:, t] = v_new
        if progress is not None and t == steps - 1:
            progress(batch)
    return EmulatorRun(out, out.sum(axis=1, dtype=np.int64), rec_s, rec_i, rec_v, saturated)


__all__ = ["EmulatorRun", "emulate_network", "rnd16", "INT32_MIN", "INT32_MAX"]
