"""The emulator's compiled kernel: the rules of ``emulator.py`` in numba, event-driven.

A spike of neuron k at step t adds its row of chip weights into a ring buffer slot
(t + 1 + delay) of the layer it projects to, so the work per step is (neuron updates) +
(spikes x fan-out), as on the chip. Samples of a batch run in parallel (``prange``).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from snncc.errors import SnnccError

Q_HALF, Q_MASK = 1 << 21, (1 << 22) - 1
U_HALF, U_MASK = 1 << 23, (1 << 24) - 1
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


@njit(cache=True, inline="always")
def _scatter(buf, ring, t, k, n_post, post_off, wflat, dflat, base, uniform):
    """Add pre neuron k's weights (row k of a transposed block starting at ``base``) into the ring."""
    row = base + k * n_post
    if uniform >= 0:
        slot = (t + 1 + uniform) % ring
        for j in range(n_post):
            buf[slot, post_off + j] += wflat[row + j]
    else:
        for j in range(n_post):
            slot = (t + 1 + dflat[row + j]) % ring
            buf[slot, post_off + j] += wflat[row + j]


@njit(cache=True, parallel=True)
def _run(x, n, noff, wflat, dflat, woff, roff, duni, druni, params, bias, ring, record_all,
         out_spikes, all_s, all_u, all_v, ovf):
    batch, steps, width = x.shape
    n_layers = n.shape[0]
    total = noff[n_layers - 1] + n[n_layers - 1]
    last = n_layers - 1
    for b in prange(batch):
        buf = np.zeros((ring, total), np.int64)
        u = np.zeros(total, np.int64)
        v = np.zeros(total, np.int64)
        ref = np.zeros(total, np.int64)
        fired = np.zeros(total, np.uint8)
        q_wraps = 0
        u_wraps = 0
        v_clips = 0
        for t in range(steps):
            slot = t % ring
            # input axons: this step's input spikes reach layer 1 one step (+ delay) later
            for k in range(width):
                if x[b, t, k]:
                    if record_all:
                        all_s[b, t, k] = 1
                    _scatter(buf, ring, t, k, n[1], noff[1], wflat, dflat, woff[1], duni[1])
            for i in range(1, n_layers):
                i_keep = 4096 - params[i, 0]
                v_keep = 4096 - params[i, 1]
                vth = params[i, 2]
                ref_delay = params[i, 3]
                vmin = params[i, 4]
                vmax = params[i, 5]
                off = noff[i]
                for j in range(off, off + n[i]):
                    q = buf[slot, j]
                    buf[slot, j] = 0
                    qw = ((q + Q_HALF) & Q_MASK) - Q_HALF
                    if qw != q:
                        q_wraps += 1
                    uu = u[j]
                    if uu >= 0:
                        ud = (uu * i_keep) >> 12
                    else:
                        ud = -(((-uu) * i_keep) >> 12)
                    ur = ud + qw
                    un = ((ur + U_HALF) & U_MASK) - U_HALF
                    if un != ur:
                        u_wraps += 1
                    vv = v[j]
                    if vv >= 0:
                        vd = (vv * v_keep) >> 12
                    else:
                        vd = -(((-vv) * v_keep) >> 12)
                    vn = vd + un + bias[j]
                    if vn > vmax:
                        vn = vmax
                        v_clips += 1
                    elif vn < vmin:
                        vn = vmin
                        v_clips += 1
                    if ref[j] > 0:
                        vn = 0
                        ref[j] -= 1
                    s = 0
                    if vn > vth:
                        s = 1
                        vn = 0
                        ref[j] = ref_delay - 1
                    u[j] = un
                    v[j] = vn
                    fired[j] = s
                    if record_all:
                        all_s[b, t, j] = s
                        all_u[b, t, j] = un
                        all_v[b, t, j] = vn
                    if i == last and s:
                        out_spikes[b, t, j - off] = 1
                # deliver this layer's spikes: to itself (recurrent) and to the next layer
                for k in range(n[i]):
                    if fired[off + k]:
                        if roff[i] >= 0:
                            _scatter(buf, ring, t, k, n[i], off, wflat, dflat, roff[i], druni[i])
                        if i < last:
                            _scatter(buf, ring, t, k, n[i + 1], noff[i + 1], wflat, dflat, woff[i + 1], duni[i + 1])
        ovf[b, 0] = q_wraps
        ovf[b, 1] = u_wraps
        ovf[b, 2] = v_clips


def _uniform(d: np.ndarray) -> int:
    return int(d.flat[0]) if d.size and np.all(d == d.flat[0]) else (-1 if d.size else 0)


def run_program(prog, network, x: np.ndarray, record: str):
    """Flatten ``prog`` for the kernel, run it on (B, T, C) uint8 ``x``, wrap the result."""
    from snncc.targets.loihi.emulator import EmulationResult, _prediction

    layers = len(prog.n)
    blocks_w, blocks_d = [], []
    woff = np.full(layers, -1, np.int64)
    roff = np.full(layers, -1, np.int64)
    duni = np.zeros(layers, np.int64)
    druni = np.zeros(layers, np.int64)
    pos = 0
    for i in range(1, layers):
        woff[i] = pos
        blocks_w.append(prog.wt[i].ravel())
        blocks_d.append(prog.dt_[i].ravel())
        duni[i] = _uniform(prog.dt_[i])
        pos += prog.wt[i].size
        if prog.wr[i].size:
            roff[i] = pos
            blocks_w.append(prog.wr[i].ravel())
            blocks_d.append(prog.dr[i].ravel())
            druni[i] = _uniform(prog.dr[i])
            pos += prog.wr[i].size
    wflat = np.ascontiguousarray(np.concatenate(blocks_w) if blocks_w else np.zeros(0, np.int64), dtype=np.int64)
    dflat = np.ascontiguousarray(np.concatenate(blocks_d) if blocks_d else np.zeros(0, np.int64), dtype=np.int64)
    batch, steps, _ = x.shape
    total = int(prog.n.sum())
    n_out = int(prog.n[-1])
    record_all = record == "all"
    if record_all and (np.any(prog.params[1:, 4] < INT32_MIN) or np.any(prog.params[1:, 5] > INT32_MAX)):
        raise SnnccError("vmin/vmax beyond 32 bits cannot be recorded", field="vmin")
    out = np.zeros((batch, steps, n_out), np.uint8)
    shape_all = (batch, steps, total) if record_all else (0, 0, 0)
    all_s = np.zeros(shape_all, np.uint8)
    all_u = np.zeros(shape_all, np.int32)
    all_v = np.zeros(shape_all, np.int32)
    ovf = np.zeros((batch, 3), np.int64)
    _run(np.ascontiguousarray(x), prog.n, prog.noff, wflat, dflat, woff, roff, duni, druni,
         prog.params, prog.bias, int(prog.ring), record_all, out, all_s, all_u, all_v, ovf)
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
