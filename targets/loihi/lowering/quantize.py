"""Quantization for Loihi 1: the paper's PyTorch-to-Loihi rules (typos fixed), as pure functions.

    w_scale = floor(256 / max_k max|W_k|)                  one integer scale for the network
    w_q     = clip(round(W * s / 2**e / 2) * 2, -256, 254)  even 8-bit mantissas, round half to even
    w_chip  = w_q * 2**(6 + e)                             e = wgtExp (0 under the paper's rule)
    split:  e per synapse = e_fine where the weight fits 8 bits at e_fine, else e_coarse
            (e_coarse fits max|W|; e_fine fits the bulk: weights within 20x the median |W|)
    vThMant = round(theta * s)                             1 <= vThMant <= 2**17 - 1
    iDecay  = int(4096 * (1 - exp(-dt / tau_syn)))         exp discretisation ("euler": int(4096*dt/tau))
    vDecay  = int(4096 * (1 - exp(-dt / tau_mem)))
    tSample = ceil(T_record / dt)
    fine:   s = min(256 / max theta, 254 * 2**7 / max|W into the layer|)  (vThMant ~ 256: a chip
            threshold of 2**14 leaves 2**9 x threshold of headroom in u and v, 2**7 in q per step);
            e per synapse = the smallest in [-6, 7] that fits (a float with an 8-bit mantissa:
            relative error <= 1/128 above 128 * 2**-6 chip units), decay registers rounded to nearest

``s`` is the layer's scale (the network's w_scale under the paper's global rule). Spikes are
binary, so each layer may carry its own scale without changing the next layer's input.
A bias on a population's current (``snncc/passes/current_bias.py``) is a weight from an always-on source on
Loihi: it is quantized as one more column of the population's feed-forward projection (same s
and e) and counts towards that projection's max|W|.
``quantize_graph`` returns a new Graph whose float parameters are the quantized ones read back
in float units (W_q * 2**e / s, theta = vThMant / s, decays 1 - register/4096) plus a
``QuantizationRecord`` saying what was done; the input graph is never modified.
The register formats and ranges are ``chip.py``'s, read at call time.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.timebase import recording_steps
from snncc.ir.nodes import LIF, Dense
from snncc.targets.kit.graphs import BiasTerm, current_biases, max_abs_bias, restore_biases
from snncc.targets.loihi import chip
from snncc.targets.loihi.options import SCALE_RULES

FINE_V_TH_MANT = 256                 # the fine rule's threshold mantissa (chip threshold 2**14)
FINE_STEPS = (1.0, 1.125, 1.25, 1.375, 1.5, 1.625, 1.75, 1.875)   # scale multipliers auto measures (one octave)
OUTLIER_RATIO = 20.0                 # |W| above 20x the median |W != 0| is an outlier


# -- small pure rules (reused by other engineers) -----------------------------------------------
def weight_scale(max_abs: float) -> int:
    """The paper's w_scale = floor(256 / max|W|); it must be >= 1 (else a weight exponent is needed)."""
    max_abs = float(max_abs)
    if not (math.isfinite(max_abs) and max_abs > 0):
        raise SnnccError(f"max |W| must be positive and finite to define w_scale, got {max_abs}", field="weights")
    span = chip.WEIGHT_SPAN
    scale = math.floor(span / max_abs)
    if scale < 1:
        raise SnnccError(f"max |W| = {max_abs:g} > {span} gives w_scale 0 under the paper's global rule; "
                         "use --scale per-layer (weight exponents)", field="weights")
    return int(scale)


def quantize_weights(weight: np.ndarray, w_scale: float, wgt_exp: int = 0) -> np.ndarray:
    """clip(round(W * w_scale / 2**wgt_exp / 2) * 2, -256, 254) as int16 (np.round: half to even)."""
    scaled = np.asarray(weight, np.float64) * (float(w_scale) / 2.0 ** wgt_exp)
    return np.clip(np.round(scaled / 2.0) * 2.0, chip.WEIGHT_MIN, chip.WEIGHT_MAX).astype(np.int16)


def synapse_exponents(values: np.ndarray, scale: float, fine: int, coarse: int) -> np.ndarray:
    """Per synapse: ``fine`` where round(W * s / 2**fine / 2) * 2 fits [-256, 254], else ``coarse``."""
    r = np.round(np.asarray(values, np.float64) * (float(scale) / 2.0 ** fine) / 2.0) * 2.0
    return np.where((r >= chip.WEIGHT_MIN) & (r <= chip.WEIGHT_MAX), fine, coarse).astype(np.int64)


def finest_exponents(values: np.ndarray, scale: float, low: int | None = None, high: int | None = None) -> np.ndarray:
    """Per synapse: the smallest e in [low, high] (default: the chip's wgtExp range, -6..7) where
    round(W * s / 2**e / 2) * 2 fits [-256, 254] (``high`` where none does: that weight is clipped,
    and counted as such).

    In closed form, linear in the synapses: with y = W * s as the rounding computes it (W * (s / 2**e) is
    y / 2**e exactly), round half to even of y / 2**(e+1) lies in [-128, 127] exactly when y < 255 * 2**e
    (y > 0) or y >= -257 * 2**e (y < 0). Writing |y| = m * 2**x (``numpy.frexp``, 1/2 <= m < 1):
    255 = (255/256) * 2**8 gives e = x - 8 when m < 255/256, else x - 7; 257 = (257/512) * 2**9 gives
    e = x - 9 when m <= 257/512, else x - 8. W = 0 fits every exponent (the lowest)."""
    low = chip.WGT_EXP_MIN if low is None else low
    high = chip.WGT_EXP_MAX if high is None else high
    y = np.asarray(values, np.float64) * float(scale)
    m, x = np.frexp(np.abs(y))
    up = chip.WEIGHT_MAX + 1                         # 255 = (WEIGHT_MAX + 1): y < 255 * 2**e for y > 0
    down = -chip.WEIGHT_MIN + 1                      # 257: |y| <= 257 * 2**e for y < 0
    pos = x.astype(np.int64) - np.where(m < up / 256.0, 8, 7)
    neg = x.astype(np.int64) - np.where(m <= down / 512.0, 9, 8)
    e = np.where(y > 0, pos, np.where(y < 0, neg, low))
    e = np.where(np.isfinite(y), e, high)
    return np.clip(e, low, high).astype(np.int64)


def bulk_max(values: np.ndarray, ratio: float = OUTLIER_RATIO) -> float:
    """max |W| over the weights within ``ratio`` x the median |W != 0| (the projection without outliers)."""
    a = np.abs(np.asarray(values, np.float64)).reshape(-1)
    nz = a[a > 0]
    if not nz.size:
        return 0.0
    return float(np.max(nz[nz <= ratio * np.median(nz)]))


def clipped_to_254(weight: np.ndarray, w_scale: float, wgt_exp: int = 0) -> int:
    """How many weights rounded to +256 (or beyond) and were clipped to 254, or below -256."""
    scaled = np.round(np.asarray(weight, np.float64) * (float(w_scale) / 2.0 ** wgt_exp) / 2.0) * 2.0
    return int(np.count_nonzero((scaled > chip.WEIGHT_MAX) | (scaled < chip.WEIGHT_MIN)))


def decay_register(dt: float, tau: float, discretisation: str = "exp", rounding: str = "truncate") -> int:
    """int(4096 * (1 - exp(-dt/tau))) for "exp", int(4096 * dt/tau) for "euler" (the paper truncates;
    ``rounding="nearest"`` rounds instead, halving the worst decay error)."""
    if not (tau > 0 and dt > 0):
        raise SnnccError("time constants and dt must be positive", field="tau")
    to_int = int if rounding == "truncate" else round
    if discretisation == "euler":
        value = int(to_int(chip.DECAY_ONE * dt / tau))
    elif discretisation == "exp":
        value = int(to_int(chip.DECAY_ONE * (1.0 - math.exp(-dt / tau))))
    else:
        raise SnnccError(f"unknown discretisation {discretisation!r}", field="discretisation")
    if not 0 <= value <= chip.DECAY_ONE:
        raise SnnccError(f"decay register {value} outside 0..{chip.DECAY_ONE} (dt/tau = {dt / tau:g}: a forward-Euler "
                         "model with dt > tau cannot be expressed)", field="tau")
    return value


def threshold_mantissa(theta: float, scale: float, layer: str = "") -> int:
    """vThMant = round(theta * scale), checked against the chip's 1 .. 2**17 - 1."""
    value = round(float(theta) * float(scale))
    if not chip.V_TH_MANT_MIN <= value <= chip.V_TH_MANT_MAX:
        raise SnnccError(f"vThMant = round({theta:g} * {scale:g}) = {value} is outside "
                         f"{chip.V_TH_MANT_MIN}..{chip.V_TH_MANT_MAX}",
                         field=f"node '{layer}'.threshold" if layer else "threshold")
    return int(value)


def samples_steps(graph: Graph, input_steps: int | None = None) -> tuple[int, str]:
    """tSample = ceil(T_record / dt) with T_record from metadata, else the input length (steps)."""
    t_record = graph.metadata.get("recording_length_s")
    if t_record is not None:
        return recording_steps(t_record, graph.dt), f"ceil({t_record} s / {graph.dt} s)"
    if input_steps is not None:
        return int(input_steps), "the input length"
    raise SnnccError("tSample needs graph.metadata['recording_length_s'] or an input length", field="recording_length_s")


# -- records -------------------------------------------------------------------------------------
@dataclass
class ProjectionQuant:
    """What quantization did to one projection (a Dense feeding a LIF)."""

    dense: str
    target: str
    scale: float            # the target layer's scale s
    wgt_exp: int
    max_abs: float
    clipped: int            # weights beyond the 8-bit range after rounding (+256 -> 254 included)
    zeroed: int             # non-zero float weights that became 0
    rms_error: float        # RMS of (W_q * 2**e / s - W), float units
    range_used: float       # max|W| * s / 2**e / 256: the fraction of the 8-bit range in use
    bias_starts: list[int] = field(default_factory=list)   # current biases carried as columns (first IR step)
    bias_max_error: float | None = None                     # max |b_q * 2**e / s - b| over those columns
    wgt_exp_outliers: int | None = None    # split: the coarse exponent of the outlier synapses (wgt_exp: the fine one)
    outliers: int = 0                      # split: synapses (bias columns included) at the coarse exponent
    per_synapse: bool = False              # fine: each synapse its finest exponent (wgt_exp: the smallest used)
    exponents_used: list[int] = field(default_factory=list)   # fine: the distinct exponents (synapse formats)

    def exponents(self, values: np.ndarray):
        """The exponent of each synapse carrying ``values``: one int, or an int array when split or fine.

        Per-synapse exponents are computed once per array (lowering asks again for the same weights while it
        builds the network); the memo is no field, so the record's ``as_dict`` never sees it."""
        if self.wgt_exp_outliers is None and not self.per_synapse:
            return self.wgt_exp
        memo = self.__dict__.setdefault("_memo", [])
        for array, found in memo:
            if array is values:
                return found
        if self.per_synapse:
            found = finest_exponents(values, self.scale)
        else:
            found = synapse_exponents(values, self.scale, self.wgt_exp, self.wgt_exp_outliers)
        memo.append((values, found))
        return found

    def mantissas(self, values: np.ndarray) -> tuple[np.ndarray, int]:
        """(``quantize_weights`` of ``values`` at their ``exponents``, how many were clipped: ``clipped_to_254``),
        rounded once per array (one pass; the lowering asks again for the same weights)."""
        memo = self.__dict__.setdefault("_mantissas", [])
        for array, found in memo:
            if array is values:
                return found
        e = self.exponents(values)
        r = np.round(np.asarray(values, np.float64) * (float(self.scale) / 2.0 ** e) / 2.0) * 2.0
        clipped = int(np.count_nonzero((r > chip.WEIGHT_MAX) | (r < chip.WEIGHT_MIN)))
        np.clip(r, chip.WEIGHT_MIN, chip.WEIGHT_MAX, out=r)
        found = (r.astype(np.int16), clipped)
        memo.append((values, found))
        return found


@dataclass
class LayerQuant:
    """Registers of one population: ints, or per-neuron lists (one compartment profile per neuron)."""

    lif: str
    scale: float
    v_th_mant: int | list[int]
    i_decay: int | list[int]
    v_decay: int | list[int]
    bias_mant: list[int] | None = None
    bias_exp: int | None = None
    bias_max_error: float | None = None


@dataclass
class QuantizationRecord:
    rule: str                           # "global" | "per-layer" | "split" (per-layer, some projections split) | "fine"
    reason: str
    w_scale: int | None                 # the network's scale under the global rule
    fine_step: float | None = None      # fine: the multiplier of the layers' scales (FINE_STEPS)
    projections: list[ProjectionQuant] = field(default_factory=list)
    layers: list[LayerQuant] = field(default_factory=list)
    clipped_total: int = 0
    calibration: dict[str, Any] | None = None   # scale="auto": measured errors before/after

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def forget(self) -> None:
        """Drop the per-synapse exponents and mantissas the projections keep (``ProjectionQuant.exponents``): a
        candidate measured and set aside holds its record, not one array per synapse."""
        for p in self.projections:
            p.__dict__.pop("_memo", None)
            p.__dict__.pop("_mantissas", None)


# -- the pass ------------------------------------------------------------------------------------
def projections(graph: Graph) -> list[tuple[str, str]]:
    """(dense, lif) pairs: every Dense whose output feeds a LIF population."""
    out = []
    for name, op in graph.items():
        if isinstance(op, Dense):
            for succ in graph.successors(name):
                if isinstance(graph.node(succ), LIF):
                    out.append((name, succ))
    return out


def bias_carrier(graph: Graph, lif: str) -> str | None:
    """The Dense that carries ``lif``'s current biases: its first feed-forward (non-self-loop) input."""
    for pred in graph.predecessors(lif):
        if isinstance(graph.node(pred), Dense) and lif not in graph.predecessors(pred):
            return pred
    return None


def projection_max(graph: Graph, dense: str, lif: str) -> float:
    """max |W| of the projection, including the current-bias columns it carries (max |W| = the larger of |max W|
    and |min W|: no temporary as large as W)."""
    w = graph.node(dense).weight
    m = max(abs(float(np.max(w))), abs(float(np.min(w)))) if w.size else 0.0
    if bias_carrier(graph, lif) == dense:
        m = max(m, max_abs_bias(graph, lif))
    return m


def per_neuron(values: np.ndarray, rule) -> np.ndarray:
    """``rule`` applied to each neuron's value (once per distinct value)."""
    uniq, inv = np.unique(np.asarray(values, np.float64), return_inverse=True)
    return np.array([rule(float(u)) for u in uniq])[inv.reshape(-1)]


def register_value(arr: np.ndarray):
    """One int when every neuron shares the register (one compartment profile), else a list of ints."""
    arr = np.asarray(arr)
    return int(arr[0]) if np.all(arr == arr[0]) else [int(a) for a in arr]


def exponent_for(max_abs: float, scale: float) -> int:
    """Smallest wgtExp in [-6, 7] with max|W| * scale / 2**e <= 256."""
    if max_abs <= 0:
        return 0
    e = math.ceil(math.log2(max_abs * scale / chip.WEIGHT_SPAN) - 1e-12)
    return int(min(max(e, chip.WGT_EXP_MIN), chip.WGT_EXP_MAX))


def layer_scales(graph: Graph, rule: str, fine_step: float = 1.0) -> tuple[dict[str, float], int | None]:
    """Per-LIF scale s: the paper's single w_scale, or floor(256 / max|W| into that layer)."""
    pairs = projections(graph)
    if not pairs:
        raise SnnccError("the graph has no Dense -> LIF projection to quantize", field="graph")
    maxima = {dense: projection_max(graph, dense, lif) for dense, lif in pairs}
    if all(m == 0 for m in maxima.values()):
        # 256 / max|W| is undefined; every scale stores zeros exactly, so take the smallest (1):
        # an all-zero network is legal, and every loader accepts it with a note
        return {lif: 1.0 for _, lif in pairs}, (1 if rule == "global" else None)
    if rule == "global":
        w_scale = weight_scale(max(maxima.values()))
        return {lif: float(w_scale) for _, lif in pairs}, w_scale
    scales: dict[str, float] = {}
    if rule == "fine":
        for _, lif in pairs:
            op = graph.node(lif)
            top = float(np.max(op.threshold)) if np.all(np.isfinite(op.threshold)) else 1.0
            s = FINE_V_TH_MANT * fine_step / top if top > 0 else 1.0
            m = max(maxima[d] for d, l in pairs if l == lif)
            if m > 0:
                s = min(s, chip.WEIGHT_MAX * 2.0 ** chip.WGT_EXP_MAX / m)
            if op.bias is not None and op.bias_placement == "voltage" and np.max(np.abs(op.bias)) > 0:
                s = min(s, chip.BIAS_MANT_MAX * 2.0 ** chip.BIAS_EXP_MAX
                        / (2.0 ** chip.V_TH_SHIFT * float(np.max(np.abs(op.bias)))))
            scales[lif] = s
        return scales, None
    for _, lif in pairs:
        m = max(maxima[d] for d, l in pairs if l == lif)
        span = chip.WEIGHT_SPAN
        scales[lif] = float(math.floor(span / m)) if 0 < m <= span else 1.0
    return scales, None


def quantize_graph(
    graph: Graph,
    rule: str = "global",
    *,
    split: set[str] | frozenset[str] = frozenset(),
    reason: str = "",
    fine_step: float = 1.0,
    graph_out: bool = True,
) -> tuple[Graph | None, QuantizationRecord]:
    """Quantize every projection and LIF of ``graph``; return (graph in quantized float units, record).

    ``rule``: "global" (the paper: one w_scale, wgtExp 0), "per-layer" (each LIF its own
    integer scale, each projection the smallest weight exponent that fits 8 bits) or "fine" (each
    LIF a scale that puts its threshold mantissa near 256, each synapse its finest exponent,
    decay registers rounded to nearest; ``fine_step`` in [1, 2) multiplies those scales: within an
    octave every scale keeps the same precision, but rounds each weight differently). Denses in
    ``split`` get two exponents (``synapse_exponents``): outliers keep the coarse one, the bulk a
    finer one; the record's rule is then "split" if any projection was split.
    """
    if rule not in ("global", "per-layer", "fine"):
        raise SnnccError(f"scale rule must be one of {SCALE_RULES}", field="--scale")
    rounding = "nearest" if rule == "fine" else "truncate"
    # graph_out False: the record alone (a candidate being measured); the weights quantized below are assigned anew
    g = graph.copy(replaced=[graph.node(d).weight for d, _ in projections(graph)]) if graph_out else None
    scales, w_scale = layer_scales(graph, rule, fine_step)
    record = QuantizationRecord(rule=rule, reason=reason, w_scale=w_scale,
                                fine_step=float(fine_step) if rule == "fine" else None)
    for dense, lif in projections(graph):
        w = graph.node(dense).weight
        s = scales[lif]
        max_abs = projection_max(graph, dense, lif)
        e = 0 if rule == "global" else exponent_for(max_abs, s)
        carried = current_biases(graph, lif) if bias_carrier(graph, lif) == dense else []
        pq = ProjectionQuant(dense=dense, target=lif, scale=s, wgt_exp=e, max_abs=max_abs, clipped=0, zeroed=0,
                             rms_error=0.0, range_used=float(max_abs * s / 2.0 ** e / chip.WEIGHT_SPAN))
        if rule == "fine":
            pq.per_synapse = True
            present = np.zeros(chip.WGT_EXP_MAX - chip.WGT_EXP_MIN + 1, bool)   # the exponents nonzero values use
            for values in [w] + [t.vector for t in carried]:
                present[np.asarray(pq.exponents(values))[values != 0] - chip.WGT_EXP_MIN] = True
            used = np.flatnonzero(present) + chip.WGT_EXP_MIN if present.any() else np.array([e])
            pq.exponents_used = [int(u) for u in used]
            pq.wgt_exp, pq.range_used = int(used.min()), float(max_abs * s / 2.0 ** int(used.max()) / chip.WEIGHT_SPAN)
        elif dense in split:
            values = np.concatenate([w.reshape(-1)] + [t.vector for t in carried])
            fine = exponent_for(bulk_max(values), s)
            if fine < e:
                pq.wgt_exp, pq.wgt_exp_outliers = fine, e
                pq.outliers = int(np.count_nonzero(pq.exponents(values) == e))
        ew = pq.exponents(w)
        wq, pq.clipped = pq.mantissas(w)
        back = wq * (2.0 ** ew / s)
        pq.zeroed = int(np.count_nonzero((wq == 0) & (w != 0)))
        diff = back - w
        pq.rms_error = float(np.sqrt(np.mean(np.square(diff, out=diff)))) if w.size else 0.0
        del diff
        if g is not None:
            g.node(dense).weight = back
        if carried:
            quantized = []
            for t in carried:
                et = pq.exponents(t.vector)
                quantized.append(BiasTerm(t.start, quantize_weights(t.vector, s, et) * (2.0 ** et / s), t.origins))
                pq.clipped += clipped_to_254(t.vector, s, et)
            pq.bias_starts = [t.start for t in carried]
            pq.bias_max_error = float(max(np.max(np.abs(q.vector - t.vector)) for q, t in zip(quantized, carried)))
            if g is not None:
                restore_biases(g, lif, quantized)
        record.projections.append(pq)
    for dense, lif in projections(graph):
        if graph.node(dense).bias is not None and bias_carrier(graph, lif) is None:
            raise SnnccError("a Dense bias needs a feed-forward projection into the population to carry it",
                             field=f"node '{dense}'.bias")
    record.clipped_total = sum(p.clipped for p in record.projections)
    if any(p.wgt_exp_outliers is not None for p in record.projections):
        record.rule = "split"
    for name, op in graph.items():
        if not isinstance(op, LIF):
            continue
        if name not in scales:
            raise SnnccError("a LIF population without an incoming Dense projection cannot be quantized",
                             field=f"node '{name}'")
        s = scales[name]
        if not np.all(np.isfinite(op.threshold)):
            raise SnnccError("a non-spiking integrator (threshold +inf) has no Loihi equivalent here: Loihi "
                             "reads out spikes", field=f"node '{name}'.threshold")
        vth = per_neuron(op.threshold, lambda th: threshold_mantissa(th, s, name))
        i_dec = per_neuron(op.tau_syn, lambda tau: decay_register(graph.dt, tau, op.discretisation, rounding))
        v_dec = per_neuron(op.tau_mem, lambda tau: decay_register(graph.dt, tau, op.discretisation, rounding))
        lq = LayerQuant(lif=name, scale=s, v_th_mant=register_value(vth), i_decay=register_value(i_dec),
                        v_decay=register_value(v_dec))
        q = g.node(name) if g is not None else SimpleNamespace()
        q.threshold = vth / s
        q.discretisation = "exp"
        # decays read back: alpha = 1 - iDecay/4096 expressed through an equivalent tau
        q.tau_syn = per_neuron(i_dec, lambda r: _tau_for(graph.dt, int(r)))
        q.tau_mem = per_neuron(v_dec, lambda r: _tau_for(graph.dt, int(r)))
        if op.bias is not None and op.bias_placement == "voltage":
            mant, bexp = bias_registers(op.bias, s)
            back = mant.astype(np.float64) * 2.0 ** bexp / (2.0 ** chip.V_TH_SHIFT * s)
            lq.bias_mant, lq.bias_exp = [int(m) for m in mant], int(bexp)
            lq.bias_max_error = float(np.max(np.abs(back - op.bias)))
            q.bias = back
        record.layers.append(lq)
    return g, record


def _tau_for(dt: float, register: int) -> float:
    """The tau whose exp decay equals 1 - register/4096 (inf when register is 0: no decay)."""
    keep = 1.0 - register / chip.DECAY_ONE
    if register == 0:
        return math.inf
    if keep <= 0:
        return 1e-300  # full decay each step
    return -dt / math.log(keep)


def bias_registers(bias: np.ndarray, scale: float) -> tuple[np.ndarray, int]:
    """Voltage bias in chip units b * s * 64 as mantissa * 2**exp (13-bit signed mantissa, exp 0..7)."""
    on_chip = np.asarray(bias, np.float64) * scale * 2.0 ** chip.V_TH_SHIFT
    peak = float(np.max(np.abs(on_chip))) if on_chip.size else 0.0
    exp = 0
    while peak / 2.0 ** exp > chip.BIAS_MANT_MAX and exp < chip.BIAS_EXP_MAX:
        exp += 1
    mant = np.round(on_chip / 2.0 ** exp)
    if np.any(np.abs(mant) > chip.BIAS_MANT_MAX):
        raise SnnccError(f"bias too large for Loihi's 13-bit mantissa with exponent <= {chip.BIAS_EXP_MAX}",
                         field="bias")
    return mant.astype(np.int64), exp


def t_sample(graph: Graph, input_steps: int | None = None) -> int:
    return samples_steps(graph, input_steps)[0]
