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
rounded up to ``LANES``; padded currents only ever receive zeros. Each weight row of the input and
recurrent matrices is kept as *spans*: runs of columns holding its non-zero weights, two runs merged
where fewer than ``SPAN_GAP`` zeros separate them (``_spans``), each span's weights stored densely. A
spike adds its row span by span, each a contiguous vector loop (adding a zero changes nothing, the
saturation included), so it costs its fan-out in vector lanes: a dense row is one span, the rows of a
replicated or relayed network a few, a scattered random row one span per synapse.

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

DENSE_FROM = 0.25            # a matrix with at least this fraction of non-zero weights is added row by whole row
SPAN_GAP = 2                 # two runs of non-zero weights of a row this close (zeros between) are one span
SPAN_MIN = 4.0               # a matrix whose spans average fewer columns is added synapse by synapse instead
DENSE, SPANS, SYNAPSES = 0, 1, 2     # how a matrix's rows are added (``_spans``)
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
    in_spans: tuple           # w_in's rows as spans: (ptr (Nin + 1,), start, length, offset, weights, mode)
    w_rec: np.ndarray         # (N, 2 NP) float32
    rec_spans: tuple          # the same for w_rec's (N) rows
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


def _spans(rows: np.ndarray, used: int, gap: int | None = None) -> tuple:
    """How the kernel adds the rows of ``rows`` (``used``: the columns that can hold weights): (ptr (rows + 1,),
    start, length, offset into weights, weights, mode). ``DENSE`` where at least ``DENSE_FROM`` of the weights are
    non-zero (the whole rows, vector loops; the spans left empty); else ``SPANS``: runs of non-zeros, merged where
    at most ``gap`` zeros lie between, each span's weights (zeros inside) stored contiguously from its offset,
    indices unsigned (no wraparound checks: vector loops); where those spans average fewer than ``SPAN_MIN``
    columns (scattered synapses), ``SYNAPSES``: every non-zero its own span, added one by one."""
    gap = SPAN_GAP if gap is None else gap
    if np.count_nonzero(rows) >= DENSE_FROM * rows.shape[0] * used:
        return _runs(np.zeros((rows.shape[0], 0), rows.dtype), gap) + (DENSE,)
    runs = _runs(rows, gap)
    if runs[1].size and float(np.mean(runs[2])) < SPAN_MIN:
        return _runs(rows, -1) + (SYNAPSES,)
    return runs + (SPANS,)


def _runs(rows: np.ndarray, gap: int) -> tuple[np.ndarray, ...]:
    """(ptr, start, length, offset, weights) of the rows' runs of non-zeros merged across at most ``gap`` zeros
    (``gap`` -1: every non-zero alone)."""
    ptr = [0]
    start, length, offset, weights = [], [], [], []
    at = 0
    for row in rows:
        idx = np.flatnonzero(row)
        if idx.size:
            cut = np.flatnonzero(np.diff(idx) > gap + 1) + 1
            for first, last in zip(np.concatenate([[0], cut]), np.concatenate([cut, [idx.size]])):
                lo, hi = int(idx[first]), int(idx[last - 1]) + 1
                start.append(lo)
                length.append(hi - lo)
                offset.append(at)
                weights.append(row[lo:hi])
                at += hi - lo
        ptr.append(len(start))
    as64 = lambda v: np.asarray(v, np.uint64)   # noqa: E731
    flat = np.concatenate(weights).astype(np.float32) if weights else np.zeros(0, np.float32)
    return as64(ptr), as64(start), as64(length), as64(offset), flat


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
    alias_ptr = np.zeros(n + 1, np.int64)
    np.cumsum([len(a) for a in spec.aliases], out=alias_ptr[1:])
    alias_idx = np.array([t for a in spec.aliases for t in a], np.int64)
    scale = lambda dash, width: _padded(np.ldexp(1.0, -np.asarray(dash, np.int64)), width)   # noqa: E731
    scale_syn = np.concatenate([scale(spec.dash_syn, np_), scale(spec.dash_syn_2, np_)])
    return Prepared(
        spec.n_in, n, n_out, spec.n_oen, np_, w_in, _spans(w_in, 2 * n), w_rec, _spans(w_rec, 2 * n), w_out_p,
        scale_syn, scale(spec.dash_mem, np_), _padded(spec.threshold, np_, 1.0), _padded(spec.bias, np_),
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
def _add_spans(cur, ptr, start, length, offset, w, j, c):
    """cur[q] = sat(cur[q] + c * w_row[q]) over row j's spans, each a contiguous vector loop (unsigned indices)."""
    r = np.uint64(j)
    for sp in range(ptr[r], ptr[r + 1]):
        q0 = start[sp]
        o = offset[sp]
        for u in range(length[sp]):
            cur[q0 + u] = min(max(cur[q0 + u] + c * w[o + u], LO), HI)


@njit(inline="always", fastmath=FAST)
def _add_synapses(cur, ptr, start, offset, w, j, c):
    """The same, synapse by synapse (each span one synapse)."""
    r = np.uint64(j)
    for sp in range(ptr[r], ptr[r + 1]):
        q = start[sp]
        cur[q] = min(max(cur[q] + c * w[offset[sp]], LO), HI)


def _signature():
    """``run_chunk``'s one signature (compiled once, cached on disk: a warm install compiles nothing)."""
    from numba import types as nt

    def arr(dtype, dims):
        return nt.Array(dtype, dims, "C")

    i64, u64, f32, u8, i16 = nt.int64, nt.uint64, nt.float32, nt.uint8, nt.int16
    spans = [arr(u64, 1)] * 4 + [arr(f32, 1), i64]
    return nt.void(arr(u8, 3), *[i64] * 6, arr(f32, 2), *spans, arr(f32, 2), *spans, arr(f32, 2),
                   *[arr(f32, 1)] * 10, arr(i64, 1), arr(i64, 1), nt.boolean, nt.boolean, arr(u8, 3), nt.boolean,
                   arr(i16, 3), arr(i16, 3), arr(i16, 3), arr(u8, 3), arr(i16, 3), arr(i16, 3))


@njit([_signature()], nogil=True, cache=True, fastmath=FAST)
def run_chunk(x, first, last, n, n_out, n_oen, np_,
              w_in, in_ptr, in_start, in_len, in_off, in_w, in_mode, w_rec, rec_ptr, rec_start, rec_len, rec_off, rec_w,
              rec_mode, w_out,
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
                    if in_mode == DENSE:
                        _add_dense(cur, w_in, j, c)
                    elif in_mode == SPANS:
                        _add_spans(cur, in_ptr, in_start, in_len, in_off, in_w, j, c)
                    else:
                        _add_synapses(cur, in_ptr, in_start, in_off, in_w, j, c)
            # 2. last step's hidden events, in neuron order
            for a in range(n_active):
                j = active[a]
                c = ev[j]
                if rec_mode == DENSE:
                    _add_dense(cur, w_rec, j, c)
                elif rec_mode == SPANS:
                    _add_spans(cur, rec_ptr, rec_start, rec_len, rec_off, rec_w, j, c)
                else:
                    _add_synapses(cur, rec_ptr, rec_start, rec_off, rec_w, j, c)
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
    args = (p.n, p.n_out, p.n_oen, p.np_, p.w_in, *p.in_spans, p.w_rec, *p.rec_spans, p.w_out,
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
