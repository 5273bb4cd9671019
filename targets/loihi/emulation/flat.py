"""The kernel's program: a network flattened once into the arrays the kernel reads (``kernel.c``, built by the
system's C compiler, ``ckernel.py``; or ``kernel.py``'s numba functions where no compiler builds it).

Numpy only: ``run_flat`` loads the kernel when a run starts (numba only where the C kernel is not used), so
building, checking or sizing a program costs no numba import. What the narrow types rely on is stated in ``kernel.py``'s
docstring and checked here (``Flat``: weights divided by their common power of two in the narrowest
integer type, the accumulator's width, 32-bit lanes where every intermediate fits, wraps skipped where
q and u cannot leave their ranges).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.loihi.emulation.ckernel import C_KERNEL, NUMBA_KERNEL, compiled, network_part, program, run_chunk
from snncc.targets.loihi.chip import DECAY_ONE, DECAY_SHIFT, Q_BITS, U_BITS

Q_HALF, Q_MASK = 1 << Q_BITS, (1 << (Q_BITS + 1)) - 1
U_HALF, U_MASK = 1 << U_BITS, (1 << (U_BITS + 1)) - 1
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
LANES = 16      # the kernel layout's unit: every layer starts at, and spans, a multiple of 16 slots


def _uniform(d: np.ndarray) -> int:
    """The one delay of a block (a broadcast single value is read without a scan), -1 when per synapse."""
    if d.size and not any(d.strides):
        return int(d.flat[0])
    return int(d.flat[0]) if d.size and np.all(d == d.flat[0]) else (-1 if d.size else 0)


def _common_shift(blocks: list[np.ndarray]) -> int:
    """The trailing zero bits shared by every non-zero chip weight of ``blocks`` (0 when all are zero)."""
    acc = 0
    for w in blocks:
        if w.size:
            acc |= int(np.bitwise_or.reduce(np.abs(w).ravel()))
    if acc == 0:
        return 0
    return (acc & -acc).bit_length() - 1


def q_u_in_range(q_max: np.ndarray, keep_u: np.ndarray) -> bool:
    """True when no neuron's q or u can ever wrap, from zero state, whatever the spikes.

    |q| <= q_max (every synapse into the neuron delivering at once). With k = keep / 4096 < 1,
    |u_t| <= k |u_(t-1)| + q_max (the decay truncates toward zero), so |u| <= q_max / (1 - k)
    = q_max * 4096 / iDecay. In range: q_max < 2**21 and q_max * 4096 < 2**23 * iDecay (iDecay =
    4096 - keep > 0); then u < 2**23 too, and neither wrap can change a value.
    """
    q_max = np.asarray(q_max, np.int64)
    i_decay = DECAY_ONE - np.asarray(keep_u, np.int64)
    if q_max.size == 0:
        return True
    if np.any(q_max >= 1 << Q_BITS) or np.any(i_decay <= 0):
        return False
    return bool(np.all(q_max * DECAY_ONE < (1 << U_BITS) * i_decay))


ACCUMULATORS = (np.int16, np.int32, np.int64)   # q accumulates in one of these ...
# ... from weights stored as int8 where they fit, else in the accumulator's own type: with the state type (int32, or
# int64 for wide runs and vmin/vmax beyond 32 bits), 12 kernel signatures in all, so that a warm numba cache holds
# every one a network can need (``KERNEL_SIGNATURES``; a small network no longer gets an int8 accumulator of its own)
KERNEL_SIGNATURES = tuple((acc, w, state) for acc in ("int16", "int32", "int64") for w in ("int8", acc)
                          for state in ("int32", "int64"))


def kernel_types(bound: int, w_min: int, w_max: int) -> tuple[type, type]:
    """(accumulator type, stored weight type) for weights in [w_min, w_max] whose per-neuron sum of |w| is at most
    ``bound``: the narrowest of ``ACCUMULATORS`` that holds +-bound (and the weights), weights as int8 where they fit,
    else in the accumulator's type (exact: every value fits, see ``kernel.py``)."""
    need = narrowest_int(min(-bound, w_min), max(bound, w_max))
    acc = next(a for a in ACCUMULATORS if np.iinfo(a).bits >= np.iinfo(need).bits)
    w = np.int8 if narrowest_int(w_min, w_max) is np.int8 else acc
    return acc, w


def narrowest_int(lo: int, hi: int):
    """The narrowest signed integer type (int8 .. int64) that holds every value in [lo, hi]."""
    for dtype in (np.int8, np.int16, np.int32):
        if np.iinfo(dtype).min <= lo and hi <= np.iinfo(dtype).max:
            return dtype
    return np.int64


def _is_sparse(block) -> bool:
    from snncc.targets.loihi.emulation.result import SparseBlock

    return isinstance(block, SparseBlock)


def _present(block) -> bool:
    """A projection exists (a SparseBlock, or a dense array that is not the (0, 0) placeholder)."""
    return _is_sparse(block) or block.size > 0


def _chip_values(block) -> np.ndarray:
    """Every stored chip weight of a block (a sparse block's synapses, a dense block's entries)."""
    return block.w if _is_sparse(block) else block


def _fan_in_abs(block, shift: int, n_post: int) -> np.ndarray:
    """sum over a block's synapses into each post neuron j of |w_chip >> shift|, as int64 (n_post,).

    Sparse: a bincount in float64, exact since every term is below 2**31 and a neuron has far
    fewer than 2**22 synapses (the total is checked against 2**53)."""
    if not _is_sparse(block):
        return np.abs(block >> shift).sum(axis=0).astype(np.int64)
    mag = np.abs(block.w >> shift)
    if int(mag.sum(dtype=np.int64)) >= 1 << 53:
        raise SnnccError("a sparse projection's weights sum beyond 2**53", field="weight")
    return np.bincount(block.post, weights=mag.astype(np.float64), minlength=n_post).astype(np.int64)


def _fits32(prog, i: int, q_max: int) -> bool:
    """Layer i's step can run in 32-bit lanes (``_update32``) without changing a bit: the largest
    |q| = |acc << shift| (``q_max``) and vThMant * 2**6 fit int32, and so does the widest v before the
    clip, |decay(v)| + |u| + |bias| <= max(|vmin|, |vmax|) + 2**23 + max |bias| (u is wrapped to 24
    bits; in-range layers stay below 2**23), which also keeps |v| below 2**31 for ``_decay32``."""
    cells = slice(int(prog.noff[i]), int(prog.noff[i] + prog.n[i]))
    vmin, vmax = int(prog.params[i, 4]), int(prog.params[i, 5])
    bias = int(np.max(np.abs(prog.bias[cells]), initial=0))
    vth = int(np.max(np.abs(prog.vth[cells]), initial=0))
    return (q_max <= INT32_MAX and vth <= INT32_MAX
            and max(abs(vmin), abs(vmax)) + (1 << U_BITS) + bias <= INT32_MAX)


class Flat:
    """A program flattened once into the kernel's arrays.

    Weights of every block (layer i's feed-forward, then its recurrent), divided by 2**shift of
    their layer, in one vector ``wflat`` in the narrowest type that holds them: the synapses of
    the sparse blocks first (grouped by source neuron; ``spost`` = their post neuron, within the
    layer; source k of the block whose pointers start at p owns synapses sptr[p + k] ..
    sptr[p + k + 1] - 1), then the dense blocks, transposed (row k = pre neuron k's fan-out).
    ``dflat`` holds the delays beside ``wflat`` (empty when every block has one delay). q
    accumulates in the narrowest type that holds the largest per-neuron sum of |w|
    (``narrowest_int``).

    Kernel layout: layer i's compartments sit at ``koff[i]`` in ``kn[i]`` = n rounded up to a
    multiple of ``LANES`` slots, so every update runs in whole vectors with no scalar remainder
    (a dense row keeps its n weights: a row's few leftover additions cost little). The padding slots get
    no synapse, decay 0, bias 0 and threshold 2**31 - 1: from zero state they stay at u = v = 0 and
    never fire (``run_flat`` updates them only where v = 0 is inside [vmin, vmax], so they never
    count a clip either).
    """

    def __init__(self, prog):
        self.prog = prog
        layers = len(prog.n)
        woff = np.full(layers, -1, np.int64)
        roff = np.full(layers, -1, np.int64)
        wsp = np.full(layers, -1, np.int64)
        rsp = np.full(layers, -1, np.int64)
        duni = np.zeros(layers, np.int64)
        druni = np.zeros(layers, np.int64)
        shift = np.zeros(layers, np.int64)
        in_range = np.zeros(layers, np.int64)
        q_max = np.zeros(layers, np.int64)
        bound = 0
        entries = []                      # (layer, recurrent?, block, delays)
        self.kn = (np.asarray(prog.n, np.int64) + LANES - 1) // LANES * LANES
        self.koff = np.concatenate([[0], np.cumsum(self.kn)[:-1]]).astype(np.int64)
        for i in range(1, layers):
            blocks = [prog.wt[i]] + ([prog.wr[i]] if _present(prog.wr[i]) else [])
            shift[i] = _common_shift([_chip_values(w) for w in blocks])
            n_post = int(prog.n[i])
            fan_in_abs = sum(_fan_in_abs(w, int(shift[i]), n_post) for w in blocks)
            bound = max(bound, int(np.max(fan_in_abs, initial=0)))
            q_max[i] = int(np.max(fan_in_abs, initial=0)) << int(shift[i])
            cells = slice(int(prog.noff[i]), int(prog.noff[i] + n_post))
            in_range[i] = int(q_u_in_range(np.asarray(fan_in_abs, np.int64) << shift[i], prog.keep_u[cells]))
            entries.append((i, False, prog.wt[i], prog.dt_[i]))
            if _present(prog.wr[i]):
                entries.append((i, True, prog.wr[i], prog.dr[i]))
        scaled_w, blocks_d, ptrs, posts = [], [], [], []
        size = ptr_size = 0
        for i, rec, w, d in sorted(entries, key=lambda e: not _is_sparse(e[2])):   # sparse blocks first
            delays = w.delay if _is_sparse(w) else d
            (druni if rec else duni)[i] = _uniform(delays)
            (roff if rec else woff)[i] = size
            if _is_sparse(w):
                (rsp if rec else wsp)[i] = ptr_size
                ptrs.append(w.ptr + size)
                posts.append(w.post)
                ptr_size += w.ptr.size
                scaled_w.append(w.w >> shift[i])
            else:
                scaled_w.append((w >> shift[i]).ravel())
            blocks_d.append(delays)                     # flattened below only when some block has per-synapse delays
            size += scaled_w[-1].size
        flat_w = np.concatenate(scaled_w) if scaled_w else np.zeros(0, np.int64)
        self.acc_dtype, w_type = kernel_types(bound, int(flat_w.min(initial=0)), int(flat_w.max(initial=0)))
        self.wflat = np.ascontiguousarray(flat_w, dtype=w_type)
        per_synapse = np.any(duni[1:] < 0) or np.any(druni[1:] < 0)
        flat_d = np.concatenate([np.ravel(d) for d in blocks_d]) if blocks_d and per_synapse else np.zeros(0, np.int64)
        self.dflat = np.ascontiguousarray(flat_d, dtype=np.int64)
        self.sptr = np.ascontiguousarray(np.concatenate(ptrs) if ptrs else np.zeros(0, np.int64), np.int64)
        self.spost = np.ascontiguousarray(np.concatenate(posts) if posts else np.zeros(0, np.int32), np.int32)
        self.woff, self.roff, self.duni, self.druni, self.shift = woff, roff, duni, druni, shift
        self.wsp, self.rsp = wsp, rsp
        self.in_range = in_range
        self.keep_u = self.kernel_layout(prog.keep_u, 0)
        self.keep_v = self.kernel_layout(prog.keep_v, 0)
        self.keep_uf = self.keep_u * 2.0**-DECAY_SHIFT   # exact: keep <= 4096, a power-of-two scale
        self.keep_vf = self.keep_v * 2.0**-DECAY_SHIFT
        self.vth = self.kernel_layout(prog.vth, INT32_MAX)
        self.bias = self.kernel_layout(prog.bias, 0)
        self._registers: dict[bool, tuple] = {}
        self.c_network: dict[bool, tuple] = {}     # wide -> ckernel.network_part (its arrays held alive with it)
        self.fits32 = np.array([0] + [int(_fits32(prog, i, int(q_max[i]))) for i in range(1, layers)], np.int64)
        self.p32 = np.ascontiguousarray(np.clip(np.stack([self.keep_u, self.keep_v, self.vth, self.bias]),
                                                INT32_MIN, INT32_MAX).astype(np.int32))


    def registers(self, wide: bool) -> tuple:
        """The kernel's per-run tables for an ordinary or a ``wide`` run, computed once each:
        ``lay`` (see ``_sample``), the wrap constants, ``kl``, the update groups, a state-type proto."""
        if wide not in self._registers:
            self._registers[wide] = _registers(self, wide)
        return self._registers[wide]

    def kernel_layout(self, values: np.ndarray, fill: int) -> np.ndarray:
        """Per-compartment int64 ``values`` (the program's layout) in the kernel's padded layout."""
        out = np.full(int(self.kn.sum()), fill, np.int64)
        for i, (lo, n) in enumerate(zip(self.prog.noff, self.prog.n)):
            out[self.koff[i]:self.koff[i] + n] = values[lo:lo + n]
        return out


def update_groups(lay: np.ndarray, inert: np.ndarray) -> np.ndarray:
    """Runs of consecutive layers 1..L the kernel updates in one pass, as (G, 2) [first, end):
    layer i joins layer i - 1's run when their ``lay`` rows (ref_delay, vmin, vmax, shift, paths)
    are equal and layer i - 1's padding lanes are inert (updated, so the pass is contiguous)."""
    runs = []
    for i in range(1, lay.shape[0]):
        if runs and np.array_equal(lay[i], lay[i - 1]) and inert[i - 1]:
            runs[-1][1] = i + 1
        else:
            runs.append([i, i + 1])
    return np.array(runs, np.int64).reshape(-1, 2)


def _registers(flat: Flat, wide: bool) -> tuple:
    prog = flat.prog
    lay = np.zeros((len(prog.n), 6), np.int64)
    lay[:, 0] = prog.params[:, 3]
    lay[:, 3] = flat.shift
    lay[:, 4] = flat.in_range
    if wide:  # no wrap, no clip: what the network computes without overflow (for the loss split)
        big = 1 << 61
        wraps = np.array([big, (big << 1) - 1, big, (big << 1) - 1], np.int64)
        lay[1:, 1], lay[1:, 2] = -big, big
    else:
        wraps = np.array([Q_HALF, Q_MASK, U_HALF, U_MASK], np.int64)
        lay[:, 1], lay[:, 2] = prog.params[:, 4], prog.params[:, 5]
    narrow = bool(np.all(lay[1:, 1] >= INT32_MIN) and np.all(lay[1:, 2] <= INT32_MAX))
    lay[:, 5] = flat.fits32 if narrow and not wide else 0
    inert = (lay[:, 1] <= 0) & (lay[:, 2] >= 0)        # v = 0 is inside [vmin, vmax]: padding lanes stay 0
    kl = np.ascontiguousarray(np.stack([flat.koff, flat.kn, np.where(inert, flat.kn, prog.n)], axis=1), np.int64)
    return lay, wraps, kl, update_groups(lay, inert), np.zeros(0, np.int32 if narrow else np.int64)


def default_threads() -> int:
    """``NUMBA_NUM_THREADS`` where set (for either kernel), else the cores this process may run on."""
    import os

    given = os.environ.get("NUMBA_NUM_THREADS", "").strip()
    if given.isdigit() and int(given) > 0:
        return int(given)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:          # not on Linux
        return max(1, os.cpu_count() or 1)


def kernel_name(flat: Flat, wide: bool = False) -> str:
    """Which kernel ``run_flat`` runs for ``flat``: ckernel.C_KERNEL or ckernel.NUMBA_KERNEL."""
    state = flat.registers(wide)[4].dtype
    return NUMBA_KERNEL if compiled(flat.acc_dtype, flat.wflat.dtype, state) is None else C_KERNEL


def run_program(prog, network, x: np.ndarray, record: str, wide: bool = False):
    """Flatten ``prog`` and run it on (B, T, C) uint8 ``x`` (see ``run_flat``)."""
    return run_flat(Flat(prog), x, record, wide)


def run_flat(flat: Flat, x: np.ndarray, record: str, wide: bool = False, threads: int | None = None):
    """Run the kernel on (B, T, C) uint8 ``x`` and wrap the result.

    ``threads``: threads to spread the batch over (default ``default_threads()``); batch 1 or ``threads=1``
    runs on the calling thread. The kernel is the C one where it builds, else numba's (``ckernel.compiled``).
    """
    from snncc.targets.loihi.emulation.result import EmulationResult, _prediction

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
    lay, wraps, kl, groups, state_proto = flat.registers(wide)
    x = np.ascontiguousarray(x, np.uint8)
    c_run = compiled(flat.acc_dtype, flat.wflat.dtype, state_proto.dtype)
    if c_run is not None:
        if wide not in flat.c_network:        # the network's part of the C kernel's program, once per flat
            flat.c_network[wide] = network_part(flat, flat.registers(wide))
        cprog, _alive = program(flat.c_network[wide][0], x, record_all, out, all_s, all_u, all_v, ovf)

        def run(lo: int, hi: int) -> None:
            run_chunk(c_run, cprog, lo, hi)
    else:
        from snncc.targets.loihi.emulation.kernel import run_chunk as numba_run

        args = (x, prog.n, prog.noff, kl, groups, lay, flat.wflat, flat.dflat, flat.woff, flat.roff, flat.duni,
                flat.druni, flat.sptr, flat.spost, flat.wsp, flat.rsp, flat.keep_u, flat.keep_v, flat.keep_uf,
                flat.keep_vf, flat.vth, flat.bias, flat.p32, int(prog.ring), record_all, out, all_s, all_u, all_v, ovf,
                wraps, np.zeros(0, flat.acc_dtype), state_proto)

        def run(lo: int, hi: int) -> None:
            numba_run(lo, hi, *args)
    workers = max(1, min(batch, default_threads() if threads is None else int(threads)))
    if workers == 1:
        run(0, batch)
    else:   # samples are independent: chunks on threads (either kernel runs without the GIL); small
        # chunks let a thread that other load slows down take fewer of them
        size = max(1, -(-batch // (4 * workers)))
        bounds = [(lo, min(lo + size, batch)) for lo in range(0, batch, size)]
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(lambda lh: run(lh[0], lh[1]), bounds))
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
