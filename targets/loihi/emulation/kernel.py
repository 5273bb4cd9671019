"""The emulator's compiled kernel: the rules of ``emulator.py`` in numba, event-driven (numba code only:
the program it reads is built by ``flat.py``, which also starts the runs, ``run_flat``). ``kernel.c`` is the
same kernel in C, which runs instead wherever the system's C compiler builds it (``ckernel.py``: no numba
start-up); the two give the same integers (tests/loihi/emulation/test_ckernel.py).

Per sample and step t:

1. one fused, vectorised pass over the compartments of a run of like layers (``update_groups``:
   the same rules and registers; their q for step t was complete before the step, so layers are
   independent within it) reads and clears ring slot t of accumulated q, applies the update of
   ``emulator.py`` and marks the neurons that fire;
2. per layer, the marks become a list of spiking neurons (64 at a time, through bit masks);
3. each spike of neuron k adds its row of weights into the ring slot ``t + 1 + delay`` of every
   layer it projects to (itself when recurrent, the next layer), four spikes' rows in one pass,
   so the work per step is (compartment updates) + (spikes x fan-out), as on the chip. A sparse
   projection (``SparseBlock``: a large mostly-zero matrix such as a folded convolution) keeps
   only its synapses, grouped by source neuron (ptr / post / w, as the chip stores them per input
   axon): a spike adds just its synapses, each to its post neuron, so its cost is its real
   fan-out, not a whole dense row.

State sits in a padded layout (``Flat``: each layer at a multiple of ``LANES`` slots, the padding
inert), so a pass is whole vectors. The hot loop uses unsigned indices, no slices and inlined
helpers: a negative-index test stops LLVM's vectoriser, and every array object created or passed
to a call costs atomic reference counts that outweighed the arithmetic.

Exactness of the narrow types (checked when the program is flattened, never assumed):

* weights are stored as ``w_chip >> shift`` (``shift``: the trailing zero bits common to every
  chip weight into a layer, so the shift loses nothing) in the narrowest of int8 .. int64 that
  holds them (dense rows and sparse synapses alike); q accumulates in the narrowest type in which
  sum_i |w_chip[j, i] >> shift| over all synapses into any neuron (feed-forward and recurrent,
  dense or sparse) fits. A ring slot holds at most one delivery per synapse, so no
  partial sum overflows, and q = acc << shift exactly.
* u, v, refractory counters are int32 when every layer's [vmin, vmax] fits 32 bits (u is wrapped
  to 24 bits, v clipped), else int64 (the overflow-free ``wide`` run). A layer whose every
  intermediate provably fits int32 (``_fits32``: q = acc << shift, vThMant * 2**6 and
  |decay(v)| + |u| + |bias|; the chip's default ranges do) runs in 32-bit lanes (``_update32``:
  8 lanes a 256-bit vector, the decay split so no product needs 64 bits, ``_decay32``); other
  32-bit-state layers compute in int64, the decays through an exact float64 product.
* a layer whose q and u cannot leave their ranges whatever the spikes (``q_u_in_range``) is
  updated without the two wraps, which could change nothing there.

A batch is split into chunks of samples run on a few Python threads (the kernel releases the
GIL; plain ``njit`` functions cache reliably and load fast, unlike a ``parallel=True`` kernel);
each chunk allocates its state once and reuses it for every sample and step.
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit.compute import sigint_deferred

with sigint_deferred():   # numba's C init would turn a Ctrl-C into an ImportError (snncc/interrupts.py)
    from numba import config, njit, types
    from numba.extending import overload

from snncc.targets.loihi.chip import DECAY_ONE, DECAY_SHIFT   # globals: numba freezes them


@njit(cache=True, inline='always')
def _add_row(buf, dst, w, src, m):
    """buf[dst:dst+m] += w[src:src+m] (one spike's weights into one ring slot; vectorised).

    Unsigned indices and no slices, here and in the hot functions below: a negative index test
    stops the vectoriser, and a slice is a new array object whose reference counting costs more
    than the additions. For the same reason the hot helpers are inlined (``inline='always'``):
    a call passing arrays pays a reference count for each."""
    for j in range(m):
        buf[np.uint64(dst + j)] += w[np.uint64(src + j)]


@njit(cache=True, inline='always')
def _add_rows4(buf, dst, w, s0, s1, s2, s3, m):
    """buf[dst + j] += w[s0 + j] + w[s1 + j] + w[s2 + j] + w[s3 + j]: four spikes' rows in one pass
    over the ring slot (a quarter of the slot's loads and stores). Exact in the accumulator's
    width: the sum is taken modulo 2**bits and its true value fits (``Flat``: any partial sum of
    the weights into a neuron does)."""
    for j in range(m):
        buf[np.uint64(dst + j)] += (w[np.uint64(s0 + j)] + w[np.uint64(s1 + j)]
                                    + w[np.uint64(s2 + j)] + w[np.uint64(s3 + j)])


@njit(cache=True, inline='always')
def _add_rows(buf, dst, w, base, spk, nspk, m):
    """The rows base + spk[c] * m (c < nspk) of ``w`` added into buf[dst:dst+m], four at a time."""
    c = 0
    while c + 4 <= nspk:
        _add_rows4(buf, dst, w, base + spk[c] * m, base + spk[c + 1] * m, base + spk[c + 2] * m,
                   base + spk[c + 3] * m, m)
        c += 4
    while c < nspk:
        _add_row(buf, dst, w, base + spk[c] * m, m)
        c += 1


@njit(cache=True)
def _add_row_delays(buf, t, ring, total, post_off, w, d, src, m):
    """A spike's weights with a delay per synapse: each goes to ring slot (t + 1 + delay) mod ring."""
    for j in range(m):
        slot = (t + 1 + d[src + j]) % ring
        buf[slot * total + post_off + j] += w[src + j]


@njit(cache=True)
def _add_synapses(buf, dst, w, post, a, b):
    """Synapses a..b-1 of a sparse block (one spike's): buf[dst + post[s]] += w[s]."""
    for s in range(a, b):
        buf[dst + post[s]] += w[s]


@njit(cache=True)
def _add_synapses_delays(buf, t, ring, total, post_off, w, post, d, a, b):
    """Sparse synapses a..b-1 with a delay each: synapse s goes to ring slot (t + 1 + d[s]) mod ring."""
    for s in range(a, b):
        buf[((t + 1 + d[s]) % ring) * total + post_off + post[s]] += w[s]


@njit(cache=True)
def _deliver(buf, t, ring, total, k, post_off, m, w, d, base, uniform):
    """Pre neuron k fired at step t: add row k of the transposed block at ``base`` into the ring."""
    src = base + k * m
    if uniform >= 0:
        _add_row(buf, ((t + 1 + uniform) % ring) * total + post_off, w, src, m)
    else:
        _add_row_delays(buf, t, ring, total, post_off, w, d, src, m)


@njit(cache=True)
def _deliver_sparse(buf, t, ring, total, spk, nspk, post_off, uniform, w, post, d, sptr, sp):
    """The spikes spk[0:nspk] of step t through a sparse block whose pointers start at sptr[sp]:
    source k adds its synapses sptr[sp + k] .. sptr[sp + k + 1] - 1, each to its own post neuron."""
    if uniform >= 0:
        dst = ((t + 1 + uniform) % ring) * total + post_off
        for c in range(nspk):
            k = spk[c]
            _add_synapses(buf, dst, w, post, sptr[sp + k], sptr[sp + k + 1])
    else:
        for c in range(nspk):
            k = spk[c]
            _add_synapses_delays(buf, t, ring, total, post_off, w, post, d, sptr[sp + k], sptr[sp + k + 1])


def _decay(x, keep, keep_f):
    """sign(x) * ((|x| * keep) >> 12), the chip's truncating decay; ``keep_f`` = keep / 4096."""
    p = int(x) * int(keep)
    return -((-p) >> DECAY_SHIFT) if p < 0 else p >> DECAY_SHIFT


@overload(_decay)
def _decay_kernel(x, keep, keep_f):
    """32-bit state: trunc(x * keep_f) in float64, exact because |x * keep| < 2**43 < 2**53 and
    keep_f = keep * 2**-12 scales by a power of two (4 lanes without a 64-bit multiply).
    64-bit state: the integer product, rounded toward zero by adding 4095 to negative products."""
    if isinstance(x, types.Integer) and x.bitwidth <= 32:
        def decay_f64(x, keep, keep_f):
            return np.int64(np.float64(x) * keep_f)
        return decay_f64

    def decay_int(x, keep, keep_f):
        p = np.int64(x) * keep
        return (p + ((p >> 63) & (DECAY_ONE - 1))) >> DECAY_SHIFT
    return decay_int


@njit(cache=True)
def _update(buf, base, u, v, ref, lo, m, keep_u, keep_v, keep_uf, keep_vf, vth, bias, ref_delay, vmin, vmax,
            shift, qh, qm, uh, um, fired, counts):
    """One step of compartments lo..lo+m-1; q is read from (and cleared in) buf[base:base+m].

    Writes fired[0:m] (0/1), adds the q-wrap / u-wrap / v-clip counts, returns the spike count.
    The decays are ``_decay`` (exact float64 product for 32-bit state, integer product otherwise).
    """
    cq = 0
    cu = 0
    cv = 0
    nf = 0
    qs = buf[base:base + m]
    us, vs, rs = u[lo:lo + m], v[lo:lo + m], ref[lo:lo + m]
    ku, kv, th, bs = keep_u[lo:lo + m], keep_v[lo:lo + m], vth[lo:lo + m], bias[lo:lo + m]
    kuf, kvf = keep_uf[lo:lo + m], keep_vf[lo:lo + m]
    for j in range(m):
        q = np.int64(qs[j]) << shift
        qs[j] = 0
        qw = ((q + qh) & qm) - qh
        ur = _decay(us[j], ku[j], kuf[j]) + qw
        un = ((ur + uh) & um) - uh
        vr = _decay(vs[j], kv[j], kvf[j]) + un + bs[j]
        vn = min(max(vr, vmin), vmax)
        cq += qw != q
        cu += un != ur
        cv += vn != vr
        r = np.int64(rs[j])
        refractory = r > 0
        vn = 0 if refractory else vn
        r = r - 1 if refractory else r
        s = vn > th[j]
        vn = 0 if s else vn
        rs[j] = ref_delay - 1 if s else r
        us[j] = un
        vs[j] = vn
        fired[j] = s
        nf += s
    counts[0] += cq
    counts[1] += cu
    counts[2] += cv
    return nf


@njit(cache=True)
def _update_in_range(buf, base, u, v, ref, lo, m, keep_u, keep_v, keep_uf, keep_vf, vth, bias, ref_delay, vmin,
                     vmax, shift, fired, counts):
    """``_update`` for a layer whose q and u provably never leave their ranges (``Flat.in_range``):
    the same arithmetic without the two wraps, which would change nothing, and their counts (0)."""
    cv = 0
    nf = 0
    qs = buf[base:base + m]
    us, vs, rs = u[lo:lo + m], v[lo:lo + m], ref[lo:lo + m]
    ku, kv, th, bs = keep_u[lo:lo + m], keep_v[lo:lo + m], vth[lo:lo + m], bias[lo:lo + m]
    kuf, kvf = keep_uf[lo:lo + m], keep_vf[lo:lo + m]
    for j in range(m):
        q = np.int64(qs[j]) << shift
        qs[j] = 0
        un = _decay(us[j], ku[j], kuf[j]) + q
        vr = _decay(vs[j], kv[j], kvf[j]) + un + bs[j]
        vn = min(max(vr, vmin), vmax)
        cv += vn != vr
        r = np.int64(rs[j])
        refractory = r > 0
        vn = 0 if refractory else vn
        r = r - 1 if refractory else r
        s = vn > th[j]
        vn = 0 if s else vn
        rs[j] = ref_delay - 1 if s else r
        us[j] = un
        vs[j] = vn
        fired[j] = s
        nf += s
    counts[2] += cv
    return nf


@njit(cache=True)
def _decay32(x, keep):
    """sign(x) * ((|x| * keep) >> 12) in 32-bit lanes, exact for |x| < 2**31 and 0 <= keep <= 4096:
    with |x| = a * 4096 + b (b < 4096), (|x| * keep) >> 12 = a * keep + ((b * keep) >> 12), and
    a * keep < 2**31, b * keep < 2**24, so no product needs 64 bits."""
    s = np.int32(x >> 31)                       # 0 or -1: |x| = (x ^ s) - s, and back
    a = np.int32((x ^ s) - s)
    d = np.int32(np.int32(a >> DECAY_SHIFT) * keep + np.int32(np.int32((a & (DECAY_ONE - 1)) * keep) >> DECAY_SHIFT))
    return np.int32((d ^ s) - s)


@njit(cache=True)
def _fire32(vr, r, lo, hi, th, rd):
    """The rest of a 32-bit step from v before the clip and the refractory counter r: returns the
    stored v, the new counter and the spike (clip; refractory hold; strict threshold; reset)."""
    zero = np.int32(0)
    vn = min(max(vr, lo), hi)
    clipped = np.int32(vn != vr)
    refractory = r > zero
    vn = zero if refractory else vn
    r = np.int32(r - np.int32(1)) if refractory else r
    s = vn > th
    return (zero if s else vn), (rd if s else r), s, clipped


@njit(cache=True, inline='always')
def _update32(buf, base, u, v, ref, lo, m, p32, ref_delay, vmin, vmax, shift, qh, qm, uh, um, wraps, fired, counts):
    """``_update`` with every intermediate in 32 bits (8 or 16 lanes a vector, no float), for a layer
    whose values provably fit (``Flat.fits32``): q = acc << shift, decay(v) + u + bias and vThMant * 2**6
    all stay within int32. ``wraps`` = 1: the q and u wraps and their counts; 0: the layer's q and u
    never leave their ranges (``q_u_in_range``), so the wraps could change nothing and are skipped.
    ``p32`` rows: 4096 - iDecay, 4096 - vDecay, vThMant * 2**6, bias (int32 per compartment).
    Plain indices, no slices: a slice is a new array object whose reference counting costs about
    as much as a hundred compartment updates."""
    sh = np.int32(shift & 31)      # < 32 visibly: the shift stays in 32-bit lanes
    qh32, qm32, uh32, um32 = np.int32(qh), np.int32(qm), np.int32(uh), np.int32(um)
    lo32, hi32 = np.int32(vmin), np.int32(vmax)
    rd = np.int32(ref_delay - 1)
    cq = np.int32(0)
    cu = np.int32(0)
    cv = np.int32(0)
    nf = np.int32(0)
    if wraps:
        for j in range(m):
            c = np.uint64(lo + j)     # unsigned indices: no wrap-around test, so the loop vectorises
            k = np.uint64(base + j)
            q = np.int32(np.int32(buf[k]) << sh)
            buf[k] = 0
            qw = np.int32(np.int32((q + qh32) & qm32) - qh32)
            ur = np.int32(_decay32(np.int32(u[c]), p32[0, c]) + qw)
            un = np.int32(np.int32((ur + uh32) & um32) - uh32)
            vr = np.int32(np.int32(_decay32(np.int32(v[c]), p32[1, c]) + un) + p32[3, c])
            vn, r, s, clipped = _fire32(vr, np.int32(ref[c]), lo32, hi32, p32[2, c], rd)
            cq = np.int32(cq + np.int32(qw != q))
            cu = np.int32(cu + np.int32(un != ur))
            cv = np.int32(cv + clipped)
            u[c], v[c], ref[c], fired[j] = un, vn, r, s
            nf = np.int32(nf + np.int32(s))
    else:
        for j in range(m):
            c = np.uint64(lo + j)     # unsigned indices: no wrap-around test, so the loop vectorises
            k = np.uint64(base + j)
            un = np.int32(_decay32(np.int32(u[c]), p32[0, c]) + np.int32(np.int32(buf[k]) << sh))
            buf[k] = 0
            vr = np.int32(np.int32(_decay32(np.int32(v[c]), p32[1, c]) + un) + p32[3, c])
            vn, r, s, clipped = _fire32(vr, np.int32(ref[c]), lo32, hi32, p32[2, c], rd)
            cv = np.int32(cv + clipped)
            u[c], v[c], ref[c], fired[j] = un, vn, r, s
            nf = np.int32(nf + np.int32(s))
    counts[0] += cq
    counts[1] += cu
    counts[2] += cv
    return nf


# byte i of a 64-bit word of 0/1 bytes -> bit i of (word * _PACK) >> 56 (no carries reach bits 56..63)
_PACK = np.uint64(0x0102040810204080)
_SHIFT56 = np.uint64(56)
# the index of a 64-bit word's single set bit: (bit * _DEBRUIJN) >> 58 is distinct for each of the 64
_DEBRUIJN = np.uint64(0x03F79D71B4CB0A89)
_SHIFT58 = np.uint64(58)
_BIT_INDEX = np.zeros(64, np.int64)
for _i in range(64):
    _BIT_INDEX[((1 << _i) * 0x03F79D71B4CB0A89 % 2**64) >> 58] = _i


@njit(cache=True)
def _spike_list(fired, m, spk):
    """Indices of the 0/1 bytes fired[0:m] that are 1, into spk; returns how many.

    ``fired`` must be padded to a multiple of 64 beyond m (``_spike_list_at`` on its words)."""
    return _spike_list_at(fired.view(np.uint64), 0, m, spk)


@njit(cache=True, inline='always')
def _spike_list_at(words, at, m, spk):
    """Indices i < m whose byte at + i is 1, in the 0/1 bytes viewed as uint64 ``words`` (a view
    made once per chunk; ``at`` a multiple of 8, 64 readable bytes past at + m); returns how many.

    64 neurons at a time: their bytes are packed into one 64-bit mask (8 neurons per multiply),
    bits past m are masked off, then the set bits are visited lowest first, so the cost follows
    the spikes rather than the neurons (spikes are rare)."""
    one = np.uint64(1)
    w0 = at >> 3
    c = 0
    for g in range((m + 63) >> 6):
        mask = np.uint64(0)
        for q in range(8):
            mask |= ((words[np.uint64(w0 + g * 8 + q)] * _PACK) >> _SHIFT56) << np.uint64(8 * q)
        rest = m - (g << 6)
        if rest < 64:
            mask &= (one << np.uint64(rest)) - one
        base = g << 6
        while mask != 0:
            low = mask & (~mask + one)
            spk[c] = base + _BIT_INDEX[(low * _DEBRUIJN) >> _SHIFT58]
            c += 1
            mask ^= low
    return c


@njit(cache=True)
def _sample(b, x, n, noff, kl, groups, lay, wflat, dflat, woff, roff, duni, druni, sptr, spost, wsp, rsp, keep_u, keep_v, keep_uf,
            keep_vf, vth, bias, p32, ring, record_all, out_spikes, all_s, all_u, all_v, ovf, wraps, buf, u, v, ref, fired,
            words, spk, counts):
    """One sample from zero state (buffers reset here): the chip's rules, step by step, layer by layer.

    ``n`` / ``noff``: neurons per layer and their offsets in the outputs; ``kl`` (L+1, 3) int64 per
    layer: its offset and padded size in the kernel's arrays (``Flat.koff`` / ``Flat.kn``) and how
    many compartments the update runs over (the padded size when padding lanes are inert, else n).
    ``groups`` (G, 2): layers first..end-1 updated in one pass (``run_flat``: same rules and
    registers, padding inert but maybe in the last).
    ``lay`` (L+1, 6) int64 per layer: ref_delay, vmin, vmax, weight shift, 1 if q and u stay in range,
    1 if the layer runs in 32-bit lanes (``_update32``; ``p32``: its int32 parameters).
    ``wsp[i]`` / ``rsp[i]``: where layer i's feed-forward / recurrent pointers start in ``sptr``
    when that block is sparse, else -1 (dense rows of n weights at ``woff[i]`` / ``roff[i]``).
    """
    steps, width = x.shape[1], x.shape[2]
    n_layers = n.shape[0]
    last = n_layers - 1
    total = kl[last, 0] + kl[last, 1]
    xflat = x.reshape(-1)
    buf[:] = 0
    u[:] = 0
    v[:] = 0
    ref[:] = 0
    counts[:] = 0
    qh, qm, uh, um = wraps[0], wraps[1], wraps[2], wraps[3]
    for t in range(steps):
        # input axons: this step's input spikes reach layer 1 one step (+ delay) later
        row = (b * steps + t) * width      # x is C-contiguous: xflat[row + k] = x[b, t, k]
        for k in range(width):
            fired[np.uint64(k)] = xflat[np.uint64(row + k)] != 0
        nspk = _spike_list_at(words, 0, width, spk)
        if record_all:
            for c in range(nspk):
                all_s[b, t, spk[c]] = 1
        if wsp[1] >= 0:
            _deliver_sparse(buf, t, ring, total, spk, nspk, kl[1, 0], duni[1], wflat, spost, dflat, sptr, wsp[1])
        elif duni[1] >= 0:
            _add_rows(buf, ((t + 1 + duni[1]) % ring) * total + kl[1, 0], wflat, woff[1], spk, nspk, n[1])
        else:
            for c in range(nspk):
                _deliver(buf, t, ring, total, spk[c], kl[1, 0], n[1], wflat, dflat, woff[1], duni[1])
        base = (t % ring) * total
        for g in range(groups.shape[0]):
            # one update over the group's layers (side by side in the kernel layout): their q for
            # step t was complete before the step began, so they are independent within it
            first, end = groups[g, 0], groups[g, 1]
            lo = kl[first, 0]
            mu = kl[end - 1, 0] + kl[end - 1, 2] - lo
            if lay[first, 5]:
                nf = _update32(buf, base + lo, u, v, ref, lo, mu, p32, lay[first, 0], lay[first, 1], lay[first, 2],
                               lay[first, 3], qh, qm, uh, um, 1 - lay[first, 4], fired, counts)
            elif lay[first, 4]:
                nf = _update_in_range(buf, base + lo, u, v, ref, lo, mu, keep_u, keep_v, keep_uf, keep_vf, vth, bias,
                                      lay[first, 0], lay[first, 1], lay[first, 2], lay[first, 3], fired, counts)
            else:
                nf = _update(buf, base + lo, u, v, ref, lo, mu, keep_u, keep_v, keep_uf, keep_vf, vth, bias,
                             lay[first, 0], lay[first, 1], lay[first, 2], lay[first, 3], qh, qm, uh, um, fired, counts)
            for i in range(first, end):
                # layer i's outputs: record, then deliver its spikes into the ring (to itself when
                # recurrent, to layer i + 1): a dense block's rows four at a time, a sparse block's
                # synapses one by one. (Inline: a call with many arrays costs a reference count each.)
                klo = kl[i, 0]
                at = klo - lo
                m = n[i]
                if record_all:
                    out_lo = noff[i]
                    for j in range(m):
                        all_s[b, t, out_lo + j] = fired[at + j]
                        all_u[b, t, out_lo + j] = u[klo + j]
                        all_v[b, t, out_lo + j] = v[klo + j]
                if nf == 0:
                    continue
                nspk = _spike_list_at(words, at, m, spk)
                if nspk == 0:
                    continue
                if i == last:
                    for c in range(nspk):
                        out_spikes[b, t, spk[c]] = 1
                if rsp[i] >= 0:                 # to itself (recurrent), sparse
                    _deliver_sparse(buf, t, ring, total, spk, nspk, klo, druni[i], wflat, spost, dflat, sptr, rsp[i])
                elif roff[i] >= 0 and druni[i] >= 0:     # to itself (recurrent)
                    _add_rows(buf, ((t + 1 + druni[i]) % ring) * total + klo, wflat, roff[i], spk, nspk, m)
                elif roff[i] >= 0:
                    for c in range(nspk):
                        _add_row_delays(buf, t, ring, total, klo, wflat, dflat, roff[i] + spk[c] * m, m)
                if i == last:
                    continue
                nxt_lo = kl[i + 1, 0]
                nxt_m = n[i + 1]
                if wsp[i + 1] >= 0:             # to the next layer, sparse
                    _deliver_sparse(buf, t, ring, total, spk, nspk, nxt_lo, duni[i + 1], wflat, spost, dflat, sptr,
                                    wsp[i + 1])
                elif duni[i + 1] >= 0:          # to the next layer
                    _add_rows(buf, ((t + 1 + duni[i + 1]) % ring) * total + nxt_lo, wflat, woff[i + 1], spk, nspk,
                              nxt_m)
                else:
                    for c in range(nspk):
                        _add_row_delays(buf, t, ring, total, nxt_lo, wflat, dflat, woff[i + 1] + spk[c] * nxt_m,
                                        nxt_m)
    ovf[b, 0] = counts[0]
    ovf[b, 1] = counts[1]
    ovf[b, 2] = counts[2]


@njit(cache=True, nogil=True)
def run_chunk(lo_b, hi_b, x, n, noff, kl, groups, lay, wflat, dflat, woff, roff, duni, druni, sptr, spost, wsp, rsp, keep_u, keep_v,
           keep_uf, keep_vf, vth, bias, p32, ring, record_all, out_spikes, all_s, all_u, all_v, ovf, wraps, acc_proto,
           state_proto):
    """Samples lo_b..hi_b-1 one after another, with state allocated once for the chunk.

    Runs without the GIL: ``run_flat`` runs chunks of a batch on several Python threads."""
    total = kl[-1, 0] + kl[-1, 1]
    buf = np.zeros(ring * total, acc_proto.dtype)
    u = np.zeros(total, state_proto.dtype)
    v = np.zeros(total, state_proto.dtype)
    ref = np.zeros(total, np.int32)
    fired = np.zeros(((max(total, x.shape[2]) + 63) & ~63) + 64, np.uint8)
    words = fired.view(np.uint64)
    spk = np.zeros(fired.shape[0] + 8, np.int32)
    counts = np.zeros(3, np.int64)
    for b in range(lo_b, hi_b):
        _sample(b, x, n, noff, kl, groups, lay, wflat, dflat, woff, roff, duni, druni, sptr, spost, wsp, rsp, keep_u, keep_v,
                keep_uf, keep_vf, vth, bias, p32, ring, record_all, out_spikes, all_s, all_u, all_v, ovf, wraps, buf, u, v,
                ref, fired, words, spk, counts)
