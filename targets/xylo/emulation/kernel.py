"""The emulator's compiled kernel: the rules of ``literal.py`` in numba, one sample at a time.

Per sample and step: (1) each input channel with c > 0 events adds c * (its weight row) to the
synaptic currents of the input expansion neurons, saturating each sum; (2) each hidden neuron
that fired c > 0 events in the previous step, in index order, does the same through its
recurrent row and, if it is an output expansion neuron, its output row; (3) one pass over the
hidden neurons decays the currents and integrates V; then the events: all at once (closed form
n = min(31, max(0, floor(V / threshold)))) when there are no aliases and every threshold is > 0,
otherwise neuron by neuron in index order (``_fire``: the closed form for a threshold > 0, the
literal loop for one <= 0), copying each neuron's events to its alias targets; the same for the
output neurons (cap 1, no aliases).

Exactness: every quantity is a whole number held in float32, exact below 2**24 in magnitude, and
none comes near: weights int16(w << shift) (computed once in ``prepare``), c * w <= 31 * 2**15,
a current plus that, two currents plus a decay and a bias <= 4 * 2**15. No operation rounds:
products and sums of such integers are exact, floor(x * 2**-dash) is x >> dash (arithmetic).
V // threshold: a correctly rounded float32 quotient of integers below 2**15 never crosses an
integer (its spacing there is below 2**-8 / threshold, the distance to the next integer at least
1 / threshold), so its floor is exact (``_fire``); the all-at-once path multiplies by 1 / threshold
instead and mends the floor with two exact checks (``_quotient``, checked against V // threshold
for every int16 V and every threshold 1 .. 32767). The fast-math flags allowed (``FAST``) exclude
reassociation and approximate division. float32 lets each pass run as 8- or 16-lane vectors.

Layout: the currents of hidden neuron k sit at k (synapse 1) and NP + k (synapse 2), NP = N
rounded up to ``LANES``; every weight row spans whole vectors (zero padding: padded currents
only ever receive zeros). A matrix that is mostly zeros is also kept as its non-zero synapses
(index, weight) per row, so a spike then costs its fan-out rather than a whole row.

Samples are independent: a batch is cut into chunks run on a few Python threads (the kernel
releases the GIL).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from snncc.targets.kit.compute import sigint_deferred

with sigint_deferred():   # numba's C init would turn a Ctrl-C into an ImportError (kit.compute)
    from numba import config, njit

from snncc.targets.xylo.chip import CORE

SPARSE_BELOW = 0.25          # a matrix with fewer non-zero weights than this fraction is run sparse
CHUNK = 16                   # samples per task handed to a thread
LANES = 16                   # rows are padded to whole vectors of this many float32


@dataclass
class Prepared:
    """A spec flattened for the kernel (weights shifted and wrapped, in the block layout)."""

    n_in: int
    n: int
    n_out: int
    n_oen: int
    np_: int                  # NP: N rounded up to LANES (synapse 2's currents start there)
    w_in: np.ndarray          # (Nin, 2 NP) float32
    in_ptr: np.ndarray        # the non-zeros of w_in per row: (Nin + 1,) int64, in_idx, in_w
    in_idx: np.ndarray
    in_w: np.ndarray
    in_dense: bool
    w_rec: np.ndarray         # (N, 2 NP) float32
    rec_ptr: np.ndarray
    rec_idx: np.ndarray
    rec_w: np.ndarray
    rec_dense: bool
    w_out: np.ndarray         # (N_oen, NOP) float32, NOP: Nout rounded up to LANES
    scale_syn: np.ndarray     # (2 NP,) float32 2**-dash_syn, 2**-dash_syn_2
    scale_mem: np.ndarray     # (NP,) float32 2**-dash_mem
    threshold: np.ndarray     # (NP,) float32 (padding: 1)
    bias: np.ndarray          # (NP,)
    scale_syn_out: np.ndarray  # (NOP,)
    scale_mem_out: np.ndarray
    threshold_out: np.ndarray
    bias_out: np.ndarray
    alias_ptr: np.ndarray     # (N + 1,) int64: the targets of k are alias_idx[alias_ptr[k]:alias_ptr[k + 1]]
    alias_idx: np.ndarray
    plain_fire: bool          # no aliases and every hidden threshold > 0: events need no index order
    plain_fire_out: bool      # every output threshold > 0


def _round_up(n: int) -> int:
    return -(-n // LANES) * LANES


def _block_rows(w: np.ndarray, np_: int) -> np.ndarray:
    """(pre, post, 2) effective weights -> (pre, 2 NP) float32 rows: synapse 1 at post, synapse 2 at NP + post."""
    out = np.zeros((w.shape[0], 2 * np_), np.float32)
    out[:, :w.shape[1]] = w[:, :, 0]
    out[:, np_:np_ + w.shape[1]] = w[:, :, 1]
    return out


def _sparse(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row-wise non-zeros of a 2-D matrix: (ptr, column index, value)."""
    nz = rows != 0
    ptr = np.zeros(rows.shape[0] + 1, np.int64)
    np.cumsum(nz.sum(axis=1), out=ptr[1:])
    r, c = np.nonzero(nz)
    return ptr, c.astype(np.int64), rows[r, c].astype(np.float32)


def _padded(values, width: int, fill: float = 0.0) -> np.ndarray:
    out = np.full(width, fill, np.float32)
    values = np.asarray(values, np.float64)
    out[:values.size] = values
    return out


def prepare(spec) -> Prepared:
    """Flatten ``spec`` (an ``XyloSpec``) for the kernel."""
    from snncc.targets.xylo.emulation.weights import effective_weights

    n, n_out = spec.n_hidden, spec.n_out
    np_, nop = _round_up(n), _round_up(n_out)
    w_in, w_rec, w_out = effective_weights(spec)
    w_in, w_rec = _block_rows(w_in, np_), _block_rows(w_rec, np_)
    w_out_p = np.zeros((spec.n_oen, nop), np.float32)
    w_out_p[:, :n_out] = w_out
    in_ptr, in_idx, in_w = _sparse(w_in)
    rec_ptr, rec_idx, rec_w = _sparse(w_rec)
    alias_ptr = np.zeros(n + 1, np.int64)
    np.cumsum([len(a) for a in spec.aliases], out=alias_ptr[1:])
    alias_idx = np.array([t for a in spec.aliases for t in a], np.int64)
    scale = lambda dash, width: _padded(np.ldexp(1.0, -np.asarray(dash, np.int64)), width)   # noqa: E731
    scale_syn = np.concatenate([scale(spec.dash_syn, np_), scale(spec.dash_syn_2, np_)])
    nonzero_in = np.count_nonzero(w_in[:, :n]) + np.count_nonzero(w_in[:, np_:np_ + n])
    nonzero_rec = np.count_nonzero(w_rec[:, :n]) + np.count_nonzero(w_rec[:, np_:np_ + n])
    return Prepared(
        spec.n_in, n, n_out, spec.n_oen, np_,
        w_in, in_ptr, in_idx, in_w, bool(nonzero_in >= SPARSE_BELOW * 2 * n * spec.n_in),
        w_rec, rec_ptr, rec_idx, rec_w, bool(nonzero_rec >= SPARSE_BELOW * 2 * n * n),
        w_out_p, scale_syn, scale(spec.dash_mem, np_), _padded(spec.threshold, np_, 1.0), _padded(spec.bias, np_),
        scale(spec.dash_syn_out, nop), scale(spec.dash_mem_out, nop), _padded(spec.threshold_out, nop, 1.0),
        _padded(spec.bias_out, nop), alias_ptr, alias_idx,
        bool(alias_idx.size == 0 and np.all(spec.threshold > 0)), bool(np.all(spec.threshold_out > 0)))


LO = np.float32(CORE.state_min)
HI = np.float32(CORE.state_max)
SPAN = np.float32(1 << CORE.state_bits)
ZERO = np.float32(0)
CAP_H = np.float32(CORE.max_hidden_spikes)
CAP_O = np.float32(CORE.max_output_spikes)
FAST = {"nnan", "ninf", "nsz", "contract"}   # no reassociation, no approximate division: all stays exact


@njit(inline="always", fastmath=FAST)
def _sat(x):
    return min(max(x, LO), HI)


@njit(inline="always", fastmath=FAST)
def _wrap(x):
    """Narrow a whole number within (-2 SPAN, 2 SPAN) to int16's range (two's complement)."""
    y = x - SPAN if x > HI else x
    return y + SPAN if y < LO else y


@njit(inline="always", fastmath=FAST)
def _decay(x, scale):
    """x >> dash (scale = 2**-dash: floor(x * scale) is that shift exactly), or sign(x) where 0."""
    d = np.floor(x * scale)
    return d if d != 0 else np.float32(x > 0) - np.float32(x < 0)


@njit(inline="always", fastmath=FAST)
def _integrate(v, current, scale_mem, bias):
    """V of one neuron after its summed currents and bias, in the order of emulator.py."""
    dv = _wrap(-_decay(v, scale_mem))
    dv = _sat(dv + current)
    dv = _sat(dv + bias)
    return _sat(v + dv)


@njit(inline="always", fastmath=FAST)
def _quotient(v, th, inv):
    """floor(v / th) for whole numbers |v| < 2**15, 0 < th < 2**15, without dividing: v * fl(1 / th)
    is within 0.01 of v / th, so its floor is off by at most one, which the two exact checks mend."""
    m = np.floor(v * inv)
    m = m + np.float32(1) if (m + np.float32(1)) * th <= v else m
    return m - np.float32(1) if m * th > v else m


@njit(inline="always", fastmath=FAST)
def _fire(v, th, n, cap):
    """(events, V) after: while V >= th and n < cap: n += 1; V = wrap(V - th)."""
    if v < th or n >= cap:
        return n, v
    if th > 0:   # V - m th never leaves int16 here: closed form
        m = min(cap - n, np.floor(v / th))
        return n + m, v - m * th
    while v >= th and n < cap:
        n += 1
        v = _wrap(v - th)
    return n, v


@njit(inline="always", fastmath=FAST)
def _add_dense(cur, w, j, c):
    """cur[q] = sat(cur[q] + c * w[j, q]) over the row (indexing w: a row view costs reference counts)."""
    for q in range(w.shape[1]):
        cur[q] = min(max(cur[q] + c * w[j, q], LO), HI)


@njit(inline="always", fastmath=FAST)
def _add_sparse(cur, idx, w, lo, hi, c):
    for p in range(lo, hi):
        q = idx[p]
        cur[q] = min(max(cur[q] + c * w[p], LO), HI)


@njit(nogil=True, cache=True, fastmath=FAST)
def run_chunk(x, first, last, n, n_out, n_oen, np_,
              w_in, in_ptr, in_idx, in_w, in_dense, w_rec, rec_ptr, rec_idx, rec_w, rec_dense, w_out,
              scale_syn, scale_mem, threshold, inv_threshold, bias, scale_syn_out, scale_mem_out, threshold_out,
              inv_threshold_out, bias_out, alias_ptr, alias_idx, plain_fire, plain_fire_out, out, record,
              r_vmem, r_isyn, r_isyn2, r_spikes, r_vmem_out, r_isyn_out):
    """Samples ``first`` .. ``last`` - 1 of ``x`` ((B, T, Nin) uint8 event counts, already <= 15)."""
    t_steps, n_in = x.shape[1], x.shape[2]
    nop = w_out.shape[1]
    cur = np.zeros(2 * np_, np.float32)
    v = np.zeros(np_, np.float32)
    ev = np.zeros(np_, np.float32)            # hidden events of the last step
    cur_o = np.zeros(nop, np.float32)
    v_o = np.zeros(nop, np.float32)
    ev_o = np.zeros(nop, np.float32)
    active = np.zeros(n, np.int64)
    off = n - n_oen
    for b in range(first, last):
        cur[:] = 0
        v[:] = 0
        ev[:] = 0
        cur_o[:] = 0
        v_o[:] = 0
        n_active = 0
        for t in range(t_steps):
            # 1. input events of this step
            for j in range(n_in):
                if x[b, t, j] != 0:
                    c = np.float32(x[b, t, j])
                    if in_dense:
                        _add_dense(cur, w_in, j, c)
                    else:
                        _add_sparse(cur, in_idx, in_w, in_ptr[j], in_ptr[j + 1], c)
            # 2. last step's hidden events, in neuron order
            for a in range(n_active):
                j = active[a]
                c = ev[j]
                if rec_dense:
                    _add_dense(cur, w_rec, j, c)
                else:
                    _add_sparse(cur, rec_idx, rec_w, rec_ptr[j], rec_ptr[j + 1], c)
                if j >= off:
                    _add_dense(cur_o, w_out, j - off, c)
            # 3. hidden neurons: the currents decay, V integrates them and the bias
            for q in range(2 * np_):
                cur[q] -= _decay(cur[q], scale_syn[q])
            for k in range(np_):
                v[k] = _integrate(v[k], cur[k] + cur[np_ + k], scale_mem[k], bias[k])
            if plain_fire:   # events of every neuron at once
                for k in range(np_):
                    m = min(max(_quotient(v[k], threshold[k], inv_threshold[k]), ZERO), CAP_H)
                    v[k] -= m * threshold[k]
                    ev[k] = m
            else:            # events in index order, copied to alias targets
                ev[:] = 0
                for k in range(n):
                    if v[k] >= threshold[k] or ev[k] != 0:
                        e, v[k] = _fire(v[k], threshold[k], ev[k], CAP_H)
                        ev[k] = e
                        for p in range(alias_ptr[k], alias_ptr[k + 1]):
                            tgt = alias_idx[p]
                            ev[tgt] = min(ev[tgt] + e, CAP_H)
            n_active = 0
            for k in range(n):
                if ev[k] != 0:
                    active[n_active] = k
                    n_active += 1
            # output neurons (one synaptic current each)
            for m in range(nop):
                cur_o[m] -= _decay(cur_o[m], scale_syn_out[m])
            for m in range(nop):
                v_o[m] = _integrate(v_o[m], cur_o[m], scale_mem_out[m], bias_out[m])
            if plain_fire_out:
                for m in range(nop):
                    e = min(max(_quotient(v_o[m], threshold_out[m], inv_threshold_out[m]), ZERO), CAP_O)
                    v_o[m] -= e * threshold_out[m]
                    ev_o[m] = e
            else:
                for m in range(n_out):
                    ev_o[m], v_o[m] = _fire(v_o[m], threshold_out[m], ZERO, CAP_O)
            for m in range(n_out):
                out[b, t, m] = np.uint8(ev_o[m])
            if record:
                for k in range(n):
                    r_vmem[b, t, k] = np.int16(v[k])
                    r_isyn[b, t, k] = np.int16(cur[k])
                    r_isyn2[b, t, k] = np.int16(cur[np_ + k])
                    r_spikes[b, t, k] = np.uint8(ev[k])
                for m in range(n_out):
                    r_vmem_out[b, t, m] = np.int16(v_o[m])
                    r_isyn_out[b, t, m] = np.int16(cur_o[m])


def _reciprocal(threshold: np.ndarray) -> np.ndarray:
    """float32 1 / threshold where the threshold is > 0 (only those are used), else 0."""
    out = np.zeros_like(threshold)
    np.divide(np.float32(1), threshold, out=out, where=threshold > 0)
    return out


def run_prepared(p: Prepared, x: np.ndarray, *, record: bool = False, threads: int | None = None):
    """Run (B, T, Nin) uint8 event counts (already clipped) through a prepared network -> ``XyloResult``."""
    from snncc.targets.kit.compute import check_memory
    from snncc.targets.xylo.emulation.result import XyloResult

    batch, t_steps, _ = x.shape
    x = np.ascontiguousarray(x, np.uint8)
    per_step = p.n_out + (p.n * 7 + p.n_out * 4 if record else 0)
    check_memory(batch * t_steps * per_step, "the emulator's outputs" + (" and recorded states" if record else ""))
    out = np.zeros((batch, t_steps, p.n_out), np.uint8)
    shape_h = (batch, t_steps, p.n) if record else (0, 0, 0)
    shape_o = (batch, t_steps, p.n_out) if record else (0, 0, 0)
    rec = (np.zeros(shape_h, np.int16), np.zeros(shape_h, np.int16), np.zeros(shape_h, np.int16),
           np.zeros(shape_h, np.uint8), np.zeros(shape_o, np.int16), np.zeros(shape_o, np.int16))
    args = (p.n, p.n_out, p.n_oen, p.np_, p.w_in, p.in_ptr, p.in_idx, p.in_w, p.in_dense,
            p.w_rec, p.rec_ptr, p.rec_idx, p.rec_w, p.rec_dense, p.w_out,
            p.scale_syn, p.scale_mem, p.threshold, _reciprocal(p.threshold), p.bias, p.scale_syn_out, p.scale_mem_out,
            p.threshold_out, _reciprocal(p.threshold_out), p.bias_out, p.alias_ptr, p.alias_idx, p.plain_fire, p.plain_fire_out, out, record, *rec)
    workers = max(1, min(-(-batch // CHUNK), config.NUMBA_NUM_THREADS if threads is None else int(threads)))
    if workers == 1:
        run_chunk(x, 0, batch, *args)
    else:
        bounds = [(lo, min(lo + CHUNK, batch)) for lo in range(0, batch, CHUNK)]
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(lambda lh: run_chunk(x, lh[0], lh[1], *args), bounds))
    return XyloResult(out, *rec) if record else XyloResult(out)
