"""The emulator's compiled kernel: the rules of ``emulator.py`` in numba, event-driven.

A spike of neuron k at step t adds its row of chip weights into a ring buffer slot
(t + 1 + delay) of the layer it projects to, so the work per step is (neuron updates) +
(spikes x fan-out), as on the chip. Samples of a batch run in parallel (``prange``).
A large mostly-zero projection (a folded convolution, a relay layer) is stored as its synapses
per source neuron (``SparseBlock``): a spike then adds only its nonzero weights, in the same
integer arithmetic, so the result is identical.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from snncc.errors import SnnccError

Q_HALF, Q_MASK = 1 << 21, (1 << 22) - 1
U_HALF, U_MASK = 1 << 23, (1 << 24) - 1
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


@njit(cache=True)
def _scatter(buf, ring, t, k, n_post, post_off, wflat, dflat, base, uniform):
    """Add pre neuron k's weights (row k of a transposed block starting at ``base``) into the ring."""
    row = base + k * n_post
    if uniform >= 0:
        slot = (t + 1 + uniform) % ring
        dst = buf[slot, post_off:post_off + n_post]
        dst += wflat[row:row + n_post]
    else:
        for j in range(n_post):
            slot = (t + 1 + dflat[row + j]) % ring
            buf[slot, post_off + j] += wflat[row + j]


@njit(cache=True)
def _scatter_sparse(buf, ring, t, k, post_off, sptr, spost, sw, sd, pbase, uniform):
    """Add pre neuron k's synapses (entries sptr[pbase + k] .. sptr[pbase + k + 1] - 1) into the ring."""
    lo = sptr[pbase + k]
    hi = sptr[pbase + k + 1]
    if uniform >= 0:
        slot = (t + 1 + uniform) % ring
        for m in range(lo, hi):
            buf[slot, post_off + spost[m]] += sw[m]
    else:
        for m in range(lo, hi):
            buf[(t + 1 + sd[m]) % ring, post_off + spost[m]] += sw[m]


@njit(cache=True, inline="always")
def _deliver(buf, ring, t, k, n_post, post_off, wflat, dflat, base, uniform, sparse_base, sptr, spost, sw, sd):
    """A spike of pre neuron k into one projection: dense block at ``base`` or sparse at ``sparse_base``."""
    if sparse_base >= 0:
        _scatter_sparse(buf, ring, t, k, post_off, sptr, spost, sw, sd, sparse_base, uniform)
    else:
        _scatter(buf, ring, t, k, n_post, post_off, wflat, dflat, base, uniform)


@njit(cache=True, parallel=True)
def _run(x, n, noff, wflat, dflat, woff, roff, duni, druni, params, bias, cells, ring, record_all,
         out_spikes, all_s, all_u, all_v, ovf, wraps, wsp, rsp, sptr, spost, sw, sd):
    for b in prange(x.shape[0]):
        _sample(b, x, n, noff, wflat, dflat, woff, roff, duni, druni, params, bias, cells, ring, record_all,
                out_spikes, all_s, all_u, all_v, ovf, wraps, wsp, rsp, sptr, spost, sw, sd)


@njit(cache=True)
def _run_serial(x, n, noff, wflat, dflat, woff, roff, duni, druni, params, bias, cells, ring, record_all,
                out_spikes, all_s, all_u, all_v, ovf, wraps, wsp, rsp, sptr, spost, sw, sd):
    for b in range(x.shape[0]):
        _sample(b, x, n, noff, wflat, dflat, woff, roff, duni, druni, params, bias, cells, ring, record_all,
                out_spikes, all_s, all_u, all_v, ovf, wraps, wsp, rsp, sptr, spost, sw, sd)


@njit(cache=True, inline="always")
def _decay(x, keep):
    """sign(x) * ((|x| * keep) >> 12) without branches: round the product toward zero."""
    p = x * keep
    return (p + ((p >> 63) & 4095)) >> 12


@njit(cache=True, inline="always")
def _compartment(j, qrow, u, v, ref, fired, bias, i_keep, v_keep, vth, ref_delay, vmin, vmax, qh, qm, uh, um):
    """Compartment j for one step; returns 1s where q wrapped, u wrapped, v clipped."""
    q = qrow[j]
    qrow[j] = 0
    qw = ((q + qh) & qm) - qh
    ur = _decay(u[j], i_keep) + qw
    un = ((ur + uh) & um) - uh
    vr = _decay(v[j], v_keep) + un + bias[j]
    vn = min(max(vr, vmin), vmax)
    clipped = np.int64(vn != vr)
    r = ref[j]
    refractory = r > 0
    vn = 0 if refractory else vn
    r = r - 1 if refractory else r
    s = vn > vth
    vn = 0 if s else vn
    ref[j] = ref_delay - 1 if s else r
    u[j] = un
    v[j] = vn
    fired[j] = s
    return np.int64(qw != q), np.int64(un != ur), clipped


@njit(cache=True)
def _update(qrow, u, v, ref, fired, bias, i_keep, v_keep, vth, ref_delay, vmin, vmax, counts, qh, qm, uh, um):
    """One step of one layer's compartments (slices of the flat state); q is read and cleared.
    One compartment profile for the whole layer (scalars: the fast, common case)."""
    cq = 0
    cu = 0
    cv = 0
    for j in range(u.shape[0]):
        a, b, c = _compartment(j, qrow, u, v, ref, fired, bias, i_keep, v_keep, vth, ref_delay, vmin, vmax,
                               qh, qm, uh, um)
        cq += a
        cu += b
        cv += c
    counts[0] += cq
    counts[1] += cu
    counts[2] += cv


@njit(cache=True)
def _update_profiles(qrow, u, v, ref, fired, bias, cells, ref_delay, vmin, vmax, counts, qh, qm, uh, um):
    """``_update`` with a profile per compartment: ``cells`` (3, n) = 4096 - iDecay, 4096 - vDecay, vThMant * 2**6."""
    cq = 0
    cu = 0
    cv = 0
    for j in range(u.shape[0]):
        a, b, c = _compartment(j, qrow, u, v, ref, fired, bias, cells[0, j], cells[1, j], cells[2, j], ref_delay,
                               vmin, vmax, qh, qm, uh, um)
        cq += a
        cu += b
        cv += c
    counts[0] += cq
    counts[1] += cu
    counts[2] += cv


@njit(cache=True)
def _sample(b, x, n, noff, wflat, dflat, woff, roff, duni, druni, params, bias, cells, ring, record_all,
            out_spikes, all_s, all_u, all_v, ovf, wraps, wsp, rsp, sptr, spost, sw, sd):
    """One sample from zero state: the chip's rules, step by step, layer by layer."""
    steps, width = x.shape[1], x.shape[2]
    n_layers = n.shape[0]
    total = noff[n_layers - 1] + n[n_layers - 1]
    last = n_layers - 1
    buf = np.zeros((ring, total), wflat.dtype)
    u = np.zeros(total, np.int64)
    v = np.zeros(total, np.int64)
    ref = np.zeros(total, np.int64)
    fired = np.zeros(total, np.uint8)
    counts = np.zeros(3, np.int64)
    for t in range(steps):
        slot = t % ring
        # input axons: this step's input spikes reach layer 1 one step (+ delay) later
        for k in range(width):
            if x[b, t, k]:
                if record_all:
                    all_s[b, t, k] = 1
                _deliver(buf, ring, t, k, n[1], noff[1], wflat, dflat, woff[1], duni[1], wsp[1], sptr, spost, sw, sd)
        for i in range(1, n_layers):
            lo = noff[i]
            hi = lo + n[i]
            if params[i, 6]:
                _update(buf[slot, lo:hi], u[lo:hi], v[lo:hi], ref[lo:hi], fired[lo:hi], bias[lo:hi],
                        params[i, 0], params[i, 1], params[i, 2], params[i, 3],
                        params[i, 4], params[i, 5], counts, wraps[0], wraps[1], wraps[2], wraps[3])
            else:
                _update_profiles(buf[slot, lo:hi], u[lo:hi], v[lo:hi], ref[lo:hi], fired[lo:hi], bias[lo:hi],
                                 cells[:, lo:hi], params[i, 3], params[i, 4], params[i, 5], counts,
                                 wraps[0], wraps[1], wraps[2], wraps[3])
            if record_all:
                for j in range(lo, hi):
                    all_s[b, t, j] = fired[j]
                    all_u[b, t, j] = u[j]
                    all_v[b, t, j] = v[j]
            # deliver this layer's spikes: to itself (recurrent) and to the next layer
            for k in range(n[i]):
                if fired[lo + k]:
                    if i == last:
                        out_spikes[b, t, k] = 1
                    if roff[i] >= 0 or rsp[i] >= 0:
                        _deliver(buf, ring, t, k, n[i], lo, wflat, dflat, roff[i], druni[i], rsp[i],
                                 sptr, spost, sw, sd)
                    if i < last:
                        _deliver(buf, ring, t, k, n[i + 1], noff[i + 1], wflat, dflat, woff[i + 1], duni[i + 1],
                                 wsp[i + 1], sptr, spost, sw, sd)
    ovf[b, 0] = counts[0]
    ovf[b, 1] = counts[1]
    ovf[b, 2] = counts[2]


def _fits_int32(prog) -> bool:
    """True when sum_i |w_chip[j, i]| over all synapses into any neuron stays below 2**31."""
    from snncc.targets.loihi.emulator import SparseBlock

    def abs_in(block) -> np.ndarray:
        return block.abs_in() if isinstance(block, SparseBlock) else np.abs(block).sum(axis=0).astype(np.float64)

    total = np.zeros(int(prog.n.sum()), np.float64)
    for i in range(1, len(prog.n)):
        lo, hi = int(prog.noff[i]), int(prog.noff[i] + prog.n[i])
        total[lo:hi] += abs_in(prog.wt[i])
        if _present(prog.wr[i]):
            total[lo:hi] += abs_in(prog.wr[i])
    return bool(total.max(initial=0) < 2**31)


def _present(block) -> bool:
    """A projection is there: a SparseBlock, or a non-empty dense block."""
    return not isinstance(block, np.ndarray) or block.size > 0


def _uniform(d: np.ndarray) -> int:
    return int(d.flat[0]) if d.size and np.all(d == d.flat[0]) else (-1 if d.size else 0)


class Flat:
    """A program flattened once into the kernel's arrays (weights in one int32/int64 vector)."""

    def __init__(self, prog):
        self.prog = prog
        from snncc.targets.loihi.emulator import SparseBlock

        layers = len(prog.n)
        blocks_w, blocks_d = [], []
        sparse_ptr, sparse_post, sparse_w, sparse_d = [np.zeros(0, np.int64)], [], [], []
        woff = np.full(layers, -1, np.int64)
        roff = np.full(layers, -1, np.int64)
        wsp = np.full(layers, -1, np.int64)      # offset of a sparse block's pointers in sptr (-1: dense)
        rsp = np.full(layers, -1, np.int64)
        duni = np.zeros(layers, np.int64)
        druni = np.zeros(layers, np.int64)
        pos, ptr_pos, syn_pos = 0, 0, 0

        def add(block, delays):
            """Append a block; returns (dense offset or -1, sparse pointer offset or -1, uniform delay)."""
            nonlocal pos, ptr_pos, syn_pos
            if isinstance(block, SparseBlock):
                sparse_ptr.append(block.ptr + syn_pos)
                sparse_post.append(block.post)
                sparse_w.append(block.w)
                sparse_d.append(block.delay)
                start = ptr_pos
                ptr_pos += block.ptr.size
                syn_pos += block.post.size
                return -1, start, _uniform(block.delay)
            blocks_w.append(block.ravel())
            blocks_d.append(delays.ravel())
            start = pos
            pos += block.size
            return start, -1, _uniform(delays)

        for i in range(1, layers):
            woff[i], wsp[i], duni[i] = add(prog.wt[i], prog.dt_[i])
            if _present(prog.wr[i]):
                roff[i], rsp[i], druni[i] = add(prog.wr[i], prog.dr[i])
        wflat = np.ascontiguousarray(np.concatenate(blocks_w) if blocks_w else np.zeros(0, np.int64), dtype=np.int64)
        sw = np.ascontiguousarray(np.concatenate(sparse_w) if sparse_w else np.zeros(0, np.int64), dtype=np.int64)
        if _fits_int32(prog):
            # every q a step can deliver fits 32 bits: accumulate in int32 (twice the SIMD width)
            wflat, sw = wflat.astype(np.int32), sw.astype(np.int32)
        dflat = np.ascontiguousarray(np.concatenate(blocks_d) if blocks_d else np.zeros(0, np.int64), dtype=np.int64)
        self.wflat, self.dflat, self.woff, self.roff, self.duni, self.druni = wflat, dflat, woff, roff, duni, druni
        self.wsp, self.rsp, self.sw = wsp, rsp, sw
        self.sptr = np.ascontiguousarray(np.concatenate(sparse_ptr), dtype=np.int64)
        self.spost = np.ascontiguousarray(np.concatenate(sparse_post) if sparse_post else np.zeros(0, np.int64),
                                          dtype=np.int64)
        self.sd = np.ascontiguousarray(np.concatenate(sparse_d) if sparse_d else np.zeros(0, np.int64), dtype=np.int64)
        self.cells = np.ascontiguousarray(np.stack([prog.keep_u, prog.keep_v, prog.vth]), dtype=np.int64)


def run_program(prog, network, x: np.ndarray, record: str, wide: bool = False):
    """Flatten ``prog`` and run it on (B, T, C) uint8 ``x`` (see ``run_flat``)."""
    return run_flat(Flat(prog), x, record, wide)


def run_flat(flat: Flat, x: np.ndarray, record: str, wide: bool = False):
    """Run the kernel on (B, T, C) uint8 ``x`` and wrap the result."""
    from snncc.targets.loihi.emulator import EmulationResult, _prediction

    prog = flat.prog
    layers = len(prog.n)
    batch, steps, _ = x.shape
    total = int(prog.n.sum())
    n_out = int(prog.n[-1])
    record_all = record == "all"
    if wide and record == "all":
        raise SnnccError("a wide (overflow-free) run records outputs only", field="record")
    if record_all and (np.any(prog.params[1:, 4] < INT32_MIN) or np.any(prog.params[1:, 5] > INT32_MAX)):
        raise SnnccError("vmin/vmax beyond 32 bits cannot be recorded", field="vmin")
    out = np.zeros((batch, steps, n_out), np.uint8)
    shape_all = (batch, steps, total) if record_all else (0, 0, 0)
    all_s = np.zeros(shape_all, np.uint8)
    all_u = np.zeros(shape_all, np.int32)
    all_v = np.zeros(shape_all, np.int32)
    ovf = np.zeros((batch, 3), np.int64)
    if wide:  # no wrap, no clip: what the network computes without overflow (for the loss split)
        big = 1 << 61
        wraps = np.array([big, (big << 1) - 1, big, (big << 1) - 1], np.int64)
        params = prog.params.copy()
        params[1:, 4], params[1:, 5] = -big, big
    else:
        wraps = np.array([Q_HALF, Q_MASK, U_HALF, U_MASK], np.int64)
        params = prog.params
    runner = _run if batch > 1 else _run_serial
    runner(np.ascontiguousarray(x), prog.n, prog.noff, flat.wflat, flat.dflat, flat.woff, flat.roff, flat.duni, flat.druni,
           params, prog.bias, flat.cells, int(prog.ring), record_all, out, all_s, all_u, all_v, ovf, wraps,
           flat.wsp, flat.rsp, flat.sptr, flat.spost, flat.sw, flat.sd)
    counts = out.sum(axis=1, dtype=np.int64)
    res = EmulationResult(output_spikes=out, counts=counts, prediction=_prediction(counts),
                          overflow={"q_wrap": int(ovf[:, 0].sum()), "u_wrap": int(ovf[:, 1].sum()),
                                    "v_clip": int(ovf[:, 2].sum())})
    if record_all:
        for i in range(layers):
            sl = slice(int(prog.noff[i]), int(prog.noff[i] + prog.n[i]))
            res.spikes[i] = np.ascontiguousarray(all_s[:, :, sl])
            if i:
                res.current[i] = all_u[:, :, sl].astype(np.int64)
                res.voltage[i] = all_v[:, :, sl].astype(np.int64)
    return res
