"""Bit-exact emulation of Loihi 1 CUBA compartments (docs/loihi.md, "One time step of a compartment").

The chip's arithmetic, per compartment and step t (integers throughout):

    q  = sum over incoming synapses of  w_chip * s_pre[t - 1 - delay]     w_chip = w * 2**(6 + wgtExp)
    q  = wrap(q, 21 bits + sign)                                          two's complement
    u  = sign(u) * ((|u| * (4096 - iDecay)) >> 12) + q ;  u = wrap(u, 23 bits + sign)
    v  = sign(v) * ((|v| * (4096 - vDecay)) >> 12) + u + bias * 2**bias_exp ;  v = clip(v, vmin, vmax)
    if refractory counter > 0:  v = 0, counter -= 1
    s  = v > vThMant * 2**6   (strict) ;  where s: v = 0, counter = refDelay - 1

Every edge (input, feed-forward, recurrent) delivers one step after the spike plus its synaptic
delay. ``reference_run`` states this literally in numpy (also runnable with float arithmetic:
no truncation, wrap or clip, used to check the lowering with quantization switched off);
``emulate`` runs the same rules in an event-driven kernel (``kernel.c`` built by the system's C compiler, or
``kernel.py`` in numba where there is none: spikes accumulate into a ring buffer of future q), the samples of a
batch spread over threads. Both count overflows.
The widths and formats are ``chip.py``'s (read at call time here; the kernel freezes them when compiled).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.compute import (FLOAT32_EXACT, MAX_STREAM_STEPS, MAX_TIME_STEPS,  # noqa: F401  (re-exported)
                                      UnitsProduct, check_memory, integer_units, spike_products, transposed,
                                      whole_number)
from snncc.targets.loihi import chip
from snncc.targets.loihi.emulation.result import EmulationResult, SparseBlock, _prediction  # noqa: F401  (re-exported)
from snncc.targets.loihi.network import LoihiNetwork

DEFAULT_GAP = 100                # blank steps between samples in stream mode (the paper's protocol)
RECORD_CHOICES = ("outputs", "all")
MODES = ("batch", "stream")


def wrap(x: np.ndarray, bits: int) -> np.ndarray:
    """Two's complement wrap of int64 values into ``bits`` magnitude bits plus a sign bit."""
    span = np.int64(1) << (bits + 1)
    half = np.int64(1) << bits
    return ((x + half) & (span - 1)) - half


def decay(x: np.ndarray, register) -> np.ndarray:
    """sign(x) * ((|x| * (4096 - register)) >> 12): the chip's truncating decay (register: one or per neuron)."""
    return np.sign(x) * ((np.abs(x) * (chip.DECAY_ONE - np.asarray(register, np.int64))) >> chip.DECAY_SHIFT)


# -- input padding ---------------------------------------------------------------------------------
def pad(x: np.ndarray, extra: int) -> np.ndarray:
    """(B, T, C) inputs with ``extra`` blank steps appended (outputs shifted later by the lowering)."""
    return np.concatenate([x, np.zeros((x.shape[0], extra, x.shape[2]), x.dtype)], axis=1) if extra else x


def lead_steps(shifts: dict[str, int], output_shift: int) -> int:
    """Blank steps to append so every population's shifted spike train fits in the run."""
    return max([int(output_shift), *(int(v) for v in shifts.values())])


# -- input checks ---------------------------------------------------------------------------------
def check_inputs(inputs, width: int, source: str | None = None) -> np.ndarray:
    """(T, C) or (B, T, C) 0/1 data (bool, ints or floats) -> (B, T, C) uint8, or a one-line error
    (the rules of ``snncc.inputs.check_batch``, shared with ``snncc run``)."""
    from snncc.targets.kit.inputs import check_batch

    x = np.asarray(inputs)
    if x.dtype.kind in "bu" and x.size and x.max() <= 1:   # unsigned and at most 1: binary (one pass)
        return check_batch(x, width, spikes=False, source=source).astype(np.uint8, copy=False)
    return check_batch(x, width, spikes=True, source=source).astype(np.uint8, copy=False)


# -- the readable statement ------------------------------------------------------------------------
def _as_delay(delay, shape: tuple[int, int]) -> np.ndarray:
    return np.broadcast_to(np.asarray(delay, np.int64), shape)


def _by_delay(weight: np.ndarray, delay, factor=1) -> list[tuple[int, "_Product"]]:
    """Split a projection ``weight * factor`` (factor a power of two) into (delay d, the product by the weights
    that have delay d) pairs.

    Sums of integer chip weights over 0/1 spikes stay far below 2**53, so a float64 matrix
    product (BLAS) gives the exact integer q; it is converted back to int64 below.
    """
    if np.ndim(delay) == 0 or np.asarray(delay).size == 1:
        return [(int(np.asarray(delay).reshape(-1)[0]), _Product(np.asarray(weight), factor))]
    d = _as_delay(delay, weight.shape)
    return [(int(v), _Product(np.where(d == v, weight, 0), factor)) for v in np.unique(d)]


SPARSE_MIN_SIZE = 1 << 20      # weight matrices this large and at most SPARSE_MAX_DENSITY full are
SPARSE_MAX_DENSITY = 0.25      # multiplied as sparse matrices (the same exact integer sums, less work)
FLOAT_UNITS_MIN_SIZE = 1 << 16  # float weights this large are searched for integer units (float32 products)


class _Product:
    """(B, n_pre) 0/1 spikes -> (B, n) = spikes @ (w * factor).T, exact for integer weights, float64 for float ones
    (``factor``: a power of two, w_chip's 2**(6 + wgtExp), applied without a scaled copy of ``w``).

    The matrix is held as w.T: scipy CSR for a large, mostly-zero matrix (a folded convolution, built from
    its nonzero entries in one scan, no dense float copy); else dense, in float32 for weights that are integers
    times a common power of two g whose every partial sum is an integer below 2**24 in units of g
    (max_j sum_i |w_ji| / g < 2**24: each sum, in any order, is exact -- the same bits as float64 -- and half the
    memory is read per step; chip weights, and the float twin of a graph quantized in chip units:
    ``kit.compute.integer_units``; multiplied by ``kit.compute.UnitsProduct``, in C where the matrix is large), else
    float64 (``kit.compute.spike_products.float_sums`` where the spikes are few enough: ascending-order sums, as
    the sparse product below takes them)."""

    def __init__(self, w: np.ndarray, factor=1):
        self.scale = 1.0
        self.w_t = self.units = None
        if w.size >= SPARSE_MIN_SIZE and np.count_nonzero(w) <= SPARSE_MAX_DENSITY * w.size:
            import scipy.sparse as sp

            rows, cols = np.nonzero(w)
            values = np.asarray(w[rows, cols], np.float64) * float(factor)
            self.w_t = sp.csr_matrix((values, (cols, rows)), shape=(w.shape[1], w.shape[0]))
        elif w.size and (w.dtype.kind in "iu" or (w.dtype.kind == "f" and w.size >= FLOAT_UNITS_MIN_SIZE)):
            found = integer_units(w)
            if found is not None:
                self.w_t, self.scale = found[0], found[1] * float(factor)
                self.units = UnitsProduct(found[0], found[2], SPARSE_MAX_DENSITY)
        if self.w_t is None:
            self.w_t = transposed(np.asarray(w, np.float64), float(factor))

    def of(self, spikes: np.ndarray) -> np.ndarray:
        """(B, n) float64: over the spikes only where they are few (the work follows them, not n_pre x n), else
        a dense product."""
        if self.units is not None:       # exact integer sums (spikes are 0 or 1)
            out = self.units.of(spikes)
            return out * self.scale if self.scale != 1.0 else out
        w_t = self.w_t
        active = np.count_nonzero(spikes)
        if active == 0:
            return np.zeros((spikes.shape[0], w_t.shape[1]))
        if isinstance(w_t, np.ndarray) and spike_products.worth_it("float", w_t.size, spikes.shape[0], active,
                                                                   w_t.shape[0]):
            out = spike_products.float_sums(np.ascontiguousarray(spikes, np.uint8), w_t)   # 0/1 spikes
            if out is not None:
                return out
        if active > SPARSE_MAX_DENSITY * spikes.size:
            out = np.asarray(spikes.astype(w_t.dtype) @ w_t)
        else:
            import scipy.sparse as sp

            rows, cols = np.nonzero(spikes)
            indptr = np.searchsorted(rows, np.arange(spikes.shape[0] + 1))
            s = sp.csr_matrix((np.ones(rows.size, w_t.dtype), cols, indptr), shape=spikes.shape)
            out = s @ w_t
            out = out.toarray() if sp.issparse(out) else np.asarray(out)
        out = out.astype(np.float64, copy=False)
        return out * self.scale if self.scale != 1.0 else out


def _delivered(history: list[np.ndarray], t: int, parts: list[tuple[int, _Product]], zero: np.ndarray) -> np.ndarray:
    """sum_i w[j, i] * s_i[t - 1 - delay[j, i]] for every post neuron j (spikes before t = 0 are 0)."""
    total = zero.copy()
    for d, product in parts:
        src = t - 1 - d
        if src >= 0:
            part = product.of(history[src])
            total = total + (part if zero.dtype.kind == "f" else np.rint(part).astype(np.int64))
    return total


def reference_run(network: LoihiNetwork, inputs, *, arithmetic: str = "int", record: str = "outputs") -> EmulationResult:
    """Batched run of the chip's rules written out plainly (slow; the statement the kernel must match).

    ``arithmetic="float"``: the same pipeline in float64 with no truncation, wrap or clip (the
    network's fields may then hold float weights, thresholds and decays). ``record``: "outputs", "all"
    (every layer's spikes, u and v) or "spikes" (every layer's spikes only).
    """
    x = network.drive(check_inputs(inputs, network.input_width))
    as_float = arithmetic == "float"
    dt = np.float64 if as_float else np.int64
    batch, steps, _ = x.shape
    layers = network.layers
    hist: list[list[np.ndarray]] = [[x[:, t].astype(dt) for t in range(steps)]]
    rec_s: dict[int, list] = {0: hist[0]}
    rec_u: dict[int, list] = {}
    rec_v: dict[int, list] = {}
    overflow = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    state = []
    for i, layer in enumerate(layers[1:], start=1):
        z = np.zeros((batch, layer.n), dt)
        state.append({"u": z.copy(), "v": z.copy(), "ref": np.zeros((batch, layer.n), np.int64)})
        hist.append([])
        rec_s[i], rec_u[i], rec_v[i] = hist[i], [], []
    def products(weight, exp, delay):   # w_chip = w * 2**(6 + wgtExp); wgtExp an int or one per synapse
        exp = np.asarray(exp, np.int64) + chip.WEIGHT_SHIFT
        factor = 2.0 ** exp if as_float else np.int64(1) << exp
        w = np.asarray(weight)
        if w.dtype.kind != ("f" if as_float else "i"):
            w = w.astype(dt)
        if exp.size == 1:                  # one power of two: applied to the product, no scaled copy
            return _by_delay(w, delay, factor.reshape(-1)[0].item())
        return _by_delay(w * factor, delay)

    ff = [None] + [products(lay.weight, lay.wgt_exp, lay.delay) for lay in layers[1:]]
    rec = [None] + [None if lay.weight_rec is None else products(lay.weight_rec, lay.wgt_exp_rec, lay.delay_rec)
                    for lay in layers[1:]]
    for t in range(steps):
        for i, layer in enumerate(layers[1:], start=1):
            st = state[i - 1]
            zero = np.zeros((batch, layer.n), dt)
            q = _delivered(hist[i - 1], t, ff[i], zero)
            if rec[i] is not None:
                q = q + _delivered(hist[i], t, rec[i], zero)
            bias = np.zeros(layer.n, dt) if layer.bias is None else np.asarray(layer.bias, dt) * (
                2.0 ** layer.bias_exp if as_float else np.int64(1) << layer.bias_exp)
            if as_float:
                u = st["u"] * ((chip.DECAY_ONE - np.asarray(layer.i_decay, np.float64)) / chip.DECAY_ONE) + q
                v = st["v"] * ((chip.DECAY_ONE - np.asarray(layer.v_decay, np.float64)) / chip.DECAY_ONE) + u + bias
            else:
                qw = wrap(q, chip.Q_BITS)
                overflow["q_wrap"] += int(np.count_nonzero(qw != q))
                u_raw = decay(st["u"], layer.i_decay) + qw
                u = wrap(u_raw, chip.U_BITS)
                overflow["u_wrap"] += int(np.count_nonzero(u != u_raw))
                v_raw = decay(st["v"], layer.v_decay) + u + bias
                v = np.clip(v_raw, layer.vmin, layer.vmax)
                overflow["v_clip"] += int(np.count_nonzero(v != v_raw))
            refractory = st["ref"] > 0
            v = np.where(refractory, 0, v)
            ref = np.where(refractory, st["ref"] - 1, st["ref"])
            threshold = np.asarray(layer.v_th_mant, dt) * (2.0 ** chip.V_TH_SHIFT if as_float else 1 << chip.V_TH_SHIFT)
            s = v > threshold
            v = np.where(s, 0, v)
            ref = np.where(s, layer.ref_delay - 1, ref)
            st["u"], st["v"], st["ref"] = u, v, ref
            hist[i].append(s.astype(dt))
            rec_u[i].append(u)
            rec_v[i].append(v)
    return _result(network, hist, rec_u, rec_v, overflow, record, batch, steps)


def _result(network, hist, rec_u, rec_v, overflow, record, batch, steps) -> EmulationResult:
    def stack(seq, n, dtype):
        return np.stack(seq, axis=1).astype(dtype) if seq else np.zeros((batch, 0, n), dtype)

    last = len(network.layers) - 1
    out = stack(hist[last], network.n_outputs, np.uint8)
    counts = out.sum(axis=1, dtype=np.int64)
    res = EmulationResult(output_spikes=out, counts=counts, prediction=_prediction(counts), overflow=overflow)
    if record in ("all", "spikes"):
        for i, layer in enumerate(network.layers):
            res.spikes[i] = stack(hist[i], layer.n, np.uint8)
            if i and record == "all":
                kind = np.float64 if rec_u[i] and rec_u[i][0].dtype.kind == "f" else np.int64
                res.current[i] = stack(rec_u[i], layer.n, kind)
                res.voltage[i] = stack(rec_v[i], layer.n, kind)
    return res


# -- the fast kernel --------------------------------------------------------------------------------
@dataclass
class Program:
    """A LoihiNetwork flattened into arrays the numba kernel reads (layers 1..L in order)."""

    n: np.ndarray            # (L+1,) neurons per layer, layer 0 = inputs
    noff: np.ndarray         # (L+1,) offset of each layer in the flat neuron arrays
    wt: list                 # per layer: feed-forward weights transposed (n_pre, n) int64, chip units,
                             # or a SparseBlock (large mostly-zero projections: only their synapses,
                             # delivered synapse by synapse by the kernel, never densified)
    dt_: list                # per layer: per-synapse delays transposed (n_pre, n) int64 (None when sparse)
    wr: list                 # recurrent (n, n) transposed, a SparseBlock, or a (0, 0) array
    dr: list
    params: np.ndarray       # (L+1, 7) int64 per layer: 4096 - iDecay, 4096 - vDecay, vThMant * 2**6 (when
                             # one profile), ref_delay, vmin, vmax, 1 if one profile for the layer else 0
    keep_u: np.ndarray       # (N,) int64 per compartment: 4096 - iDecay
    keep_v: np.ndarray       # (N,) int64: 4096 - vDecay
    vth: np.ndarray          # (N,) int64: vThMant * 2**6
    bias: np.ndarray         # (N,) int64 chip units
    ring: int                # ring buffer length (max total delay + 1)


def _chip_weights(weight, exp, where: str) -> np.ndarray:
    """w_chip = w * 2**(6 + wgtExp) as int64 (an integer only for wgtExp >= -6); wgtExp an int or per synapse."""
    exp = np.asarray(exp, np.int64)
    if exp.size and exp.min() < chip.WGT_EXP_MIN:
        raise SnnccError(f"wgtExp below {chip.WGT_EXP_MIN} gives fractional chip weights", field=where)
    return np.asarray(weight, np.int64) << (chip.WEIGHT_SHIFT + exp)


def _sparse_eligible(weight) -> bool:
    w = np.asarray(weight)
    return w.size >= SPARSE_MIN_SIZE and np.count_nonzero(w) <= SPARSE_MAX_DENSITY * w.size


def _sparse_block(weight, exp, delay, where: str) -> SparseBlock:
    """The nonzero synapses of ``weight`` (n_post, n_pre) as a SparseBlock, chip units."""
    w = np.asarray(weight)
    post, pre = np.nonzero(w)
    order = np.lexsort((post, pre))
    post, pre = post[order].astype(np.int64), pre[order].astype(np.int64)
    e = np.asarray(exp, np.int64)
    e = e if e.ndim == 0 else e[post, pre]
    if np.size(e) and np.min(e) < chip.WGT_EXP_MIN:
        raise SnnccError(f"wgtExp below {chip.WGT_EXP_MIN} gives fractional chip weights", field=where)
    w_chip = w[post, pre].astype(np.int64) << (chip.WEIGHT_SHIFT + e)
    d = np.asarray(delay, np.int64)
    d = np.full(post.size, int(d.reshape(-1)[0]) if d.size else 0, np.int64) if d.size <= 1 else d[post, pre]
    ptr = np.searchsorted(pre, np.arange(w.shape[1] + 1)).astype(np.int64)
    return SparseBlock(int(w.shape[1]), int(w.shape[0]), ptr, post, np.ascontiguousarray(w_chip), d)


def _block(weight, exp, delay, where: str):
    """(weights, delays) of one projection for the kernel: dense transposed, or a SparseBlock and None. One delay
    for the whole projection stays one value, broadcast (no array of equal entries)."""
    if _sparse_eligible(weight):
        return _sparse_block(weight, exp, delay, where), None
    e = np.asarray(exp, np.int64)
    if e.size and e.min() < chip.WGT_EXP_MIN:
        raise SnnccError(f"wgtExp below {chip.WGT_EXP_MIN} gives fractional chip weights", field=where)
    w_t = np.ascontiguousarray(np.asarray(weight).T, dtype=np.int64)       # transposed once, shifted in place
    w_t <<= (chip.WEIGHT_SHIFT + (e.T if e.ndim else e))
    d = np.asarray(delay, np.int64)
    if d.size <= 1:
        return w_t, np.broadcast_to(d.reshape(-1)[:1].reshape(()) if d.size else np.int64(0), w_t.shape)
    return w_t, np.ascontiguousarray(_as_delay(delay, np.asarray(weight).shape).T)


def _max_delay(w, d) -> int:
    if isinstance(w, SparseBlock):
        return int(w.delay.max(initial=0))
    return int(d.max(initial=0))


def program(network: LoihiNetwork) -> Program:
    layers = network.layers
    n = np.array([lay.n for lay in layers], np.int64)
    noff = np.concatenate([[0], np.cumsum(n)[:-1]]).astype(np.int64)
    empty = np.zeros((0, 0), np.int64)
    wt, dts, wr, dr = [empty], [empty], [empty], [empty]
    params = np.zeros((len(layers), 7), np.int64)
    keep_u, keep_v, vth = (np.zeros(int(n.sum()), np.int64) for _ in range(3))
    bias = np.zeros(int(n.sum()), np.int64)
    max_delay = 0
    for i, lay in enumerate(layers[1:], start=1):
        w, d = _block(lay.weight, lay.wgt_exp, lay.delay, f"/layer/{i}/neuron/wgtExp")
        wt.append(w)
        dts.append(d)
        max_delay = max(max_delay, _max_delay(w, d))
        if lay.weight_rec is not None:
            r, drr = _block(lay.weight_rec, lay.wgt_exp_rec, lay.delay_rec, f"/layer/{i}/neuron/wgtExpRec")
            wr.append(r)
            dr.append(drr)
            max_delay = max(max_delay, _max_delay(r, drr))
        else:
            wr.append(empty)
            dr.append(empty)
        cells = slice(noff[i], noff[i] + lay.n)
        keep_u[cells] = chip.DECAY_ONE - np.asarray(lay.i_decay, np.int64)
        keep_v[cells] = chip.DECAY_ONE - np.asarray(lay.v_decay, np.int64)
        vth[cells] = np.asarray(lay.v_th_mant, np.int64) * (1 << chip.V_TH_SHIFT)
        one = all(np.all(a[cells] == a[cells][0]) for a in (keep_u, keep_v, vth)) if lay.n else True
        params[i] = (keep_u[cells][0], keep_v[cells][0], vth[cells][0], lay.ref_delay, lay.vmin, lay.vmax, int(one))
        if lay.bias is not None:
            bias[noff[i]:noff[i] + lay.n] = np.asarray(lay.bias, np.int64) << lay.bias_exp
    return Program(n, noff, wt, dts, wr, dr, params, keep_u, keep_v, vth, bias, max_delay + 2)


class PreparedNetwork:
    """A network flattened once for the kernel (as a network is loaded onto the chip once).

    ``run`` takes the arguments of ``emulate``; use it to emulate many inputs without re-flattening.
    """

    def __init__(self, network: LoihiNetwork):
        from snncc.targets.loihi.emulation.flat import Flat

        self.network = network
        self.flat = Flat(program(network))

    def _check_size(self, total_steps: int, record: str) -> None:
        self.check_size(self.network, total_steps, record)

    @staticmethod
    def check_size(network: LoihiNetwork, total_steps: int, record: str) -> None:
        """What the run records must fit in memory: 1 byte per spike, 8 per recorded u and v."""
        units = sum(lay.n for lay in network.layers)
        per_step = network.layers[-1].n + (units * 17 if record == "all" else 0) + units * 16
        check_memory(total_steps * per_step, f"emulating {total_steps:,} steps of {units:,} units (record {record!r})",
                     field="input")

    @staticmethod
    def _check_stream(batch: int, steps: int, gap) -> None:
        """--gap: a whole number of blank steps, 0..MAX_TIME_STEPS, the whole stream within MAX_STREAM_STEPS."""
        gap = whole_number(gap, field="--gap", minimum=0)
        if gap > MAX_TIME_STEPS:
            raise SnnccError(f"{gap:,} blank steps exceed snncc's cap of {MAX_TIME_STEPS:,} steps "
                             "(snncc.limits.MAX_TIME_STEPS)", field="--gap")
        total = batch * (steps + gap)
        if total > MAX_STREAM_STEPS:
            raise SnnccError(f"the stream of {batch} sample(s) x ({steps} steps + {gap} gap steps) = {total:,} steps "
                             f"exceeds snncc's cap of {MAX_STREAM_STEPS:,} (snncc.limits.MAX_STREAM_STEPS)",
                             field="--gap")

    def run(self, inputs, *, record: str = "outputs", mode: str = "batch", gap: int | None = None,
            wide: bool = False, threads: int | None = None) -> EmulationResult:
        """``threads``: threads the samples of a batch are spread over (default: ``flat.default_threads()``)."""
        from snncc.targets.loihi.emulation.flat import run_flat

        if record not in RECORD_CHOICES:
            raise SnnccError(f"record must be one of {RECORD_CHOICES}", field="record")
        if mode not in MODES:
            raise SnnccError(f"mode must be one of {MODES}", field="mode")
        x = check_inputs(inputs, self.network.input_width)
        batch, steps, width = x.shape
        if mode == "batch":
            if gap is not None:
                raise SnnccError("applies only to stream mode (--stream, the paper's protocol); batch mode starts "
                                 "every sample from zero state", field="--gap")
            self._check_size(batch * steps, record)
            return run_flat(self.flat, self.network.drive(x), record, wide, threads=threads)
        gap = DEFAULT_GAP if gap is None else gap
        self._check_stream(batch, steps, gap)
        self._check_size(batch * (steps + gap), record)
        period = steps + gap
        stream = np.zeros((1, batch * period, width), np.uint8)
        for b in range(batch):
            stream[0, b * period:b * period + steps] = x[b]
        whole = run_flat(self.flat, self.network.drive(stream), record, wide)
        windows = [slice(b * period, b * period + steps) for b in range(batch)]

        def cut(a: np.ndarray) -> np.ndarray:
            return np.stack([a[0, w] for w in windows], axis=0)

        out = cut(whole.output_spikes)
        counts = out.sum(axis=1, dtype=np.int64)
        res = EmulationResult(output_spikes=out, counts=counts, prediction=_prediction(counts), overflow=whole.overflow)
        for name in ("spikes", "voltage", "current"):
            getattr(res, name).update({i: cut(a) for i, a in getattr(whole, name).items()})
        return res


def emulate(
    network: LoihiNetwork,
    inputs,
    *,
    record: str = "outputs",
    mode: str = "batch",
    gap: int | None = None,
    wide: bool = False,
) -> EmulationResult:
    """Run ``network`` bit-exactly on 0/1 ``inputs`` (T, C) or (B, T, C).

    ``inputs`` carry the model's channels; always-on bias axons (``lowering/bias_sources.py``) are added
    here, held at 1 on every step (gaps included). mode "batch": every sample starts from zero state. mode "stream": the paper's protocol, one
    continuous run with ``gap`` blank steps (default 100) after each sample; each sample's outputs are the
    steps of its own window. record "all" keeps every layer's spikes, u and v. ``wide=True``
    (outputs only) removes the q/u wrap and the v clip, to measure what overflow costs.
    """
    return PreparedNetwork(network).run(inputs, record=record, mode=mode, gap=gap, wide=wide)
