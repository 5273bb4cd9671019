"""Float chip-form populations -> the integer spec dict (gains, offsets, shifts, rounding).

Gains are per neuron (the threshold is per neuron), as large as the calibration states allow with a margin;
a weight matrix shares one left shift; rounding is to nearest or with error feedback under each neuron's
quadratic form (``kit.compute.round_with_feedback``).

Hidden populations fill the reservoir in chain order; the first receives the input weights, each
later one the previous one's spikes through the recurrent matrix, every population its own loop
there too; the readout population's weights leave the last hidden population. State ranges come
from the calibration run (teacher-forced: the float graph's spikes through the chip-form weights).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.compute import round_with_feedback, transposed
from snncc.targets.xylo.lowering import decays, sigma_delta as relay_rules
from snncc.targets.xylo.lowering.chip_form import (BIAS_SOURCE, SAFE_WEIGHT_SHIFT, SINGLE_THRESHOLD, STATE_MARGIN,
                                                   STATE_MAX, MIN_GAIN, WEIGHT_MAX, WEIGHT_MIN, HiddenFloat,
                                                   OutputFloat)
from snncc.targets.xylo.lowering.compiled import synaptic


@dataclass
class PopulationRecord:
    name: str
    role: str                   # "hidden" | "output"
    method: str                 # "single" | "direct" | "native"
    neurons: tuple[int, int]    # [start, stop) in its pool
    dashes: dict[str, list[int]]
    fit: str
    rounding: str
    gain: dict[str, float]      # chip units per threshold: min / median / max
    notes: list[str] = field(default_factory=list)
    units: tuple[float, ...] = ()   # per neuron, chip units per IR threshold (not in the record: the gain spread is)
    copies: int = 1                 # replicas side by side in ``neurons`` (copy k: the k-th block of equal size)

    def as_dict(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()
                if k != "units" and (k != "copies" or v != 1)}

    def copy_neurons(self) -> np.ndarray:
        """(copies, n) chip neuron indices: row k is copy k of the population."""
        return np.arange(self.neurons[0], self.neurons[1]).reshape(self.copies, -1)


STATE_SAMPLES = 32           # samples whose currents are held at once (``hidden_state_limit``)
SPARSE_BELOW = 0.05          # a weight matrix with fewer non-zero weights than this drives the currents sparse


def _driven(part: np.ndarray, a: float, w: np.ndarray) -> np.ndarray:
    """The synaptic traces of ``part`` (s, T, m spike trains; ``synaptic(part, a)``) through ``w.T`` (w: (n, m)), as
    (s, T, n): dense, or sparse where ``w`` is (a large sparse network's cost then grows with its synapses, not with
    n x m; the traces are handed to the sparse product channel-major, as it reads them, transposed in blocks)."""
    s, t, m = part.shape
    rows = synaptic(part, a)
    if w.size and np.count_nonzero(w) < SPARSE_BELOW * w.size:
        from scipy.sparse import csr_matrix

        traces = transposed(rows)
        del rows
        return (csr_matrix(w) @ traces).T.reshape(s, t, w.shape[0])
    return rows.reshape(s, t, m) @ w.T


def _currents(pop: HiddenFloat, trains: dict[str, np.ndarray], s0: int, s1: int) -> np.ndarray:
    """(2, s1 - s0, T, n) chip-form currents of ``pop`` driven by samples s0 .. s1 - 1 of ``trains`` (IR units)."""
    first = trains[next(iter(trains))]
    shape = (s1 - s0, first.shape[1])
    out = []
    for k in range(2):
        a = float(decays.grid(pop.dash_syn[0, k]))
        total = 0.0
        for src, w in pop.weights.items():
            if np.any(w[k]):
                total = total + _driven(trains[src][s0:s1], a, w[k])
        out.append(np.broadcast_to(total, shape + (pop.n,)) if np.isscalar(total) else total)
    return np.stack(out)


def hidden_state_limit(pop: HiddenFloat, trains: dict[str, np.ndarray], v_pre: np.ndarray) -> np.ndarray:
    """The largest gain (chip units per IR unit) each neuron's calibration states allow (the currents computed
    ``STATE_SAMPLES`` samples at a time)."""
    i_max = np.full(pop.n, -np.inf)
    v_min = np.full(pop.n, np.inf)
    for s0 in range(0, v_pre.shape[0], STATE_SAMPLES):
        cur = _currents(pop, trains, s0, min(v_pre.shape[0], s0 + STATE_SAMPLES))
        i_max = np.maximum(i_max, np.abs(cur).max(axis=(0, 1, 2)))
        if pop.method == "single":
            v_min = np.minimum(v_min, (cur.sum(0) + pop.bias).min(axis=(0, 1)))
    if pop.method == "single":
        v_min = np.minimum(v_min, 0.0)
        # V_c = G V + off with off = 16385 - G theta must stay above -32768 (with margin); currents in int16
        lim_v = (SINGLE_THRESHOLD + (STATE_MAX + 1) / STATE_MARGIN) / np.maximum(pop.theta - v_min, 1e-12)
        lim_i = STATE_MAX / (STATE_MARGIN * np.maximum(i_max, 1e-12))
        return np.minimum(np.minimum(lim_v, lim_i), (SINGLE_THRESHOLD - 1) / pop.theta)
    v_abs = np.maximum(np.abs(v_pre).max(axis=(0, 1)), pop.theta)
    return STATE_MAX / (STATE_MARGIN * np.maximum(np.maximum(i_max, v_abs), 1e-12))


def output_state_limit(out: OutputFloat, pre: np.ndarray, v_pre: np.ndarray) -> np.ndarray:
    """The largest gain each output neuron's calibration states allow (``STATE_SAMPLES`` samples at a time)."""
    i_max = np.zeros(out.n)
    steps = pre.shape[1]
    for s0 in range(0, pre.shape[0], STATE_SAMPLES):
        part = pre[s0:s0 + STATE_SAMPLES]
        for d in np.unique(out.dash_syn):
            sel = out.dash_syn == d
            cur = synaptic(part, float(decays.grid(d))).reshape((part.shape[0], steps, part.shape[2])) \
                @ out.weight[sel].T
            i_max[sel] = np.maximum(i_max[sel], np.abs(cur).max(axis=(0, 1)))
    v_abs = np.maximum(np.abs(v_pre).max(axis=(0, 1)), out.theta)
    return STATE_MAX / (STATE_MARGIN * np.maximum(np.maximum(i_max, v_abs), 1e-12))


def integer_spec(hidden: list[HiddenFloat], output: OutputFloat | None, n_inputs: int, input_source: str,
             limits: dict[str, np.ndarray], out_limit: np.ndarray | None, rounding: str,
             relays: list[relay_rules.Relay] = (), shifts: tuple[int, int] | None = None) -> tuple[dict, list[PopulationRecord]]:
    """The spec dict and a record per population. ``rounding``: "feedback" (error feedback under each population's
    hessians where it has them), "nearest", or "none" (weights left unrounded and unclipped, float64 in chip units:
    a spec only the float twin runs, to measure what rounding costs; thresholds, biases, dashes and relays as the
    chip has them).
    ``limits``: per hidden population its state-limited gains;
    ``relays`` (``relays.py``): placed after the populations, their registers under the matrices' shifts;
    ``shifts``: the input and recurrent matrices' left shifts (None: chosen here, ``choose_gains``).
    ``output`` None: the readout population is the last of ``hidden`` and the output neurons copy its spikes
    one step later, exactly (``_copy_readout``)."""
    starts, at = {}, 0
    for p in hidden:
        starts[p.name] = at
        at += p.n
    for r in relays:
        starts[r.name] = at
        at += r.n
    if output is None:
        starts[READOUT_COPY] = at
        at += hidden[-1].n
    source = any(BIAS_SOURCE in p.weights for p in hidden) or (output is not None and output.bias_source)
    if source:                       # the always-on neuron that carries biases: the last hidden neuron
        starts[BIAS_SOURCE] = at
        at += 1
    n = at
    # per hidden neuron, its largest |weight| (threshold units) in the input and the recurrent matrix
    w_in_max = np.zeros(n)
    w_rec_max = np.zeros(n)
    state = np.zeros(n)
    theta = np.zeros(n)
    for p in hidden:
        sl = slice(starts[p.name], starts[p.name] + p.n)
        theta[sl] = p.theta
        state[sl] = limits[p.name] * p.theta          # gains per threshold
        for src, w in p.weights.items():
            m = np.abs(w).max(axis=(0, 2)) / p.theta
            if src == input_source:
                w_in_max[sl] = np.maximum(w_in_max[sl], m)
            else:
                w_rec_max[sl] = np.maximum(w_rec_max[sl], m)
    if source:
        theta[starts[BIAS_SOURCE]] = 1.0
        state[starts[BIAS_SOURCE]] = SINGLE_THRESHOLD - 1
    gains, (s_in, s_rec) = choose_gains(state, [w_in_max, w_rec_max], shifts)
    gains = np.floor(gains)
    unrounded = rounding == "none"
    w_type = np.float64 if unrounded else np.int8
    spec: dict[str, Any] = {
        "weights_in": np.zeros((n_inputs, n, 2), w_type), "weights_rec": np.zeros((n, n, 2), w_type),
        "dash_syn": np.zeros(n, np.uint8), "dash_syn_2": np.zeros(n, np.uint8), "dash_mem": np.zeros(n, np.uint8),
        "threshold": np.zeros(n, np.int16), "bias": np.zeros(n, np.int16),
        "weight_shift_in": int(s_in), "weight_shift_rec": int(s_rec),
    }
    records = []
    for p in hidden:
        s0 = starts[p.name]
        sl = slice(s0, s0 + p.n)
        g = gains[sl] / p.theta                      # chip units per IR unit
        spec["dash_syn"][sl], spec["dash_syn_2"][sl] = p.dash_syn[:, 0], p.dash_syn[:, 1]
        spec["dash_mem"][sl] = p.dash_mem
        names = [s for s, k in p.columns if k == 0] if p.columns else list(p.weights)
        for j in range(p.n):
            coeffs, steps, blocks = [], [], []
            for k in range(2):
                for src in names:
                    shift = s_in if src == input_source else s_rec
                    row = p.weights[src][k, j]
                    coeffs.append(row)
                    steps.append(np.full(row.size, 2.0 ** shift / g[j]))
                    blocks.append((src, k, row.size))
            c, st = np.concatenate(coeffs), np.concatenate(steps)
            h = p.hessians[j] if (rounding == "feedback" and p.hessians is not None) else None
            if unrounded:
                ints, bias_units = c / st, p.bias[j] * g[j]
            elif h is not None and h.shape[0] == c.size + 1:          # the constant column: the bias register
                c_full = np.concatenate([c, [p.bias[j]]])
                st_full = np.concatenate([st, [1.0 / g[j]]])
                low = np.concatenate([np.full(c.size, WEIGHT_MIN), [-STATE_MAX]])
                high = np.concatenate([np.full(c.size, WEIGHT_MAX), [STATE_MAX]])
                ints_full = round_with_feedback(h, c_full, st_full, low, high, last=c.size)
                ints, bias_units = ints_full[:-1], float(ints_full[-1])
            else:
                ints = to_int(c, st, h if (h is not None and h.shape[0] == c.size) else None)
                bias_units = p.bias[j] * g[j]
            at = 0
            for src, k, size in blocks:
                vals = ints[at:at + size].astype(w_type)
                at += size
                if src == input_source:
                    spec["weights_in"][:, s0 + j, k] = vals
                else:
                    src_start = starts[src]
                    spec["weights_rec"][src_start:src_start + size, s0 + j, k] = vals
            big_g = int(round(gains[s0 + j]))
            if p.method == "single":
                off = SINGLE_THRESHOLD - big_g
                spec["threshold"][s0 + j] = SINGLE_THRESHOLD
                spec["bias"][s0 + j] = saturating_int16(off + bias_units)
            else:
                spec["threshold"][s0 + j] = big_g
                spec["bias"][s0 + j] = saturating_int16(bias_units)
        records.append(PopulationRecord(
            p.name, "hidden", p.method, (s0, s0 + p.n),
            {"dash_syn": sorted({int(v) for v in p.dash_syn[:, 0]}), "dash_syn_2": sorted({int(v) for v in p.dash_syn[:, 1]}),
             "dash_mem": sorted({int(v) for v in p.dash_mem})},
            p.fit, rounding if p.hessians is not None else "nearest", _spread(gains[sl]),
            units=tuple(float(v) for v in gains[sl])))
    for r in relays:
        shift = s_in if r.source == input_source else s_rec
        _place_relay(spec, r, starts, r.source == input_source, shift)
        r0 = starts[r.name]
        records.append(PopulationRecord(
            r.name, "relay", "sigma-delta", (r0, r0 + r.n),
            {"dash_syn": [r.dash], "dash_mem": [relay_rules.RELAY_DASH_MEM]}, "fixed", "-",
            {k: r.gain(shift) for k in ("min", "median", "max")},
            [f"events per unit of the filtered train: {r.gain(shift):.3g} (registers: weight, threshold "
             f"{r.registers(shift)})"]))
    if source:                       # no input, memoryless, V = bias = threshold: exactly one spike every step
        k = starts[BIAS_SOURCE]
        spec["threshold"][k] = SINGLE_THRESHOLD
        spec["bias"][k] = SINGLE_THRESHOLD
        records[len(hidden) - 1].notes.append(f"hidden neuron {k} is the always-on bias source")
    if output is None:
        records[len(hidden) - 1].role = "readout"
        spec.update(_copy_readout(spec, hidden[-1], starts, s_rec, n))
        records.append(PopulationRecord(hidden[-1].name, "output", "copy", (0, hidden[-1].n),
                                        {"dash_syn_out": [1], "dash_mem_out": [0]}, "exact", "-",
                                        {"min": 1.0, "median": 1.0, "max": 1.0},
                                        [f"the output neurons copy hidden neurons {starts[hidden[-1].name]}.."
                                         f"{starts[hidden[-1].name] + hidden[-1].n - 1} one step later (exact)"],
                                        units=(float(COPY_WEIGHT // 2),) * hidden[-1].n))
        if np.any(spec["threshold"] < 1):
            raise SnnccError("a threshold rounds below 1 chip unit", field="threshold")
        return spec, records
    # output neurons
    m = output.n
    o_max = np.abs(output.weight).max(axis=1) / output.theta
    o_gain, (s_out,) = choose_gains(out_limit * output.theta, [o_max])
    o_gain = np.floor(o_gain)
    g = o_gain / output.theta
    w_out = np.zeros((n, m), w_type)
    src0 = starts[output.source]
    n_src = output.weight.shape[1] - (1 if output.bias_source else 0)
    for j in range(m):
        st = np.full(output.weight.shape[1], 2.0 ** s_out / g[j])
        h = output.hessians[j] if (rounding == "feedback" and output.hessians is not None) else None
        ints = output.weight[j] / st if unrounded else to_int(output.weight[j], st, h).astype(np.int8)
        w_out[src0:src0 + n_src, j] = ints[:n_src]
        if output.bias_source:
            w_out[starts[BIAS_SOURCE], j] = ints[n_src]
    spec.update({
        "weights_out": w_out, "weight_shift_out": int(s_out),
        "dash_syn_out": output.dash_syn.astype(np.uint8), "dash_mem_out": output.dash_mem.astype(np.uint8),
        "threshold_out": saturating_int16(o_gain).astype(np.int16),
        "bias_out": saturating_int16(output.bias * g).astype(np.int16),
        "aliases": [[] for _ in range(n)],
    })
    if np.any(spec["threshold_out"] < 1) or np.any(spec["threshold"] < 1):
        raise SnnccError("a threshold rounds below 1 chip unit", field="threshold")
    records.append(PopulationRecord(output.name, "output", "native", (0, m),
                                    {"dash_syn_out": sorted({int(v) for v in output.dash_syn}),
                                     "dash_mem_out": sorted({int(v) for v in output.dash_mem})},
                                    output.fit, rounding if output.hessians is not None else "nearest", _spread(o_gain),
                                    units=tuple(float(v) for v in o_gain)))
    return spec, records


# -- gains, shifts, integers --------------------------------------------------------------------

def _shift_for(max_abs_chip: float) -> int:
    """Smallest left shift with max|w| / 2^s <= 127 (clipped to the safe range)."""
    if max_abs_chip <= WEIGHT_MAX:
        return 0
    return int(min(SAFE_WEIGHT_SHIFT, np.ceil(np.log2(max_abs_chip / WEIGHT_MAX))))


def choose_gains(state_limit: np.ndarray, weight_max: list[np.ndarray],
                 shifts: tuple[int, ...] | None = None) -> tuple[np.ndarray, list[int]]:
    """Per-neuron gains (chip units per threshold) and one shift per weight matrix.

    ``state_limit``: the largest gain each neuron's states allow; ``weight_max``: per matrix, each neuron's
    largest |weight| in threshold units. The shift of a matrix is the smallest under which every neuron keeps
    min(state_limit, MIN_GAIN); a neuron's gain is then the largest both its states and every matrix's
    int8 range allow, so weights use their 8 bits wherever the states leave room. ``shifts`` given: those
    shifts (the gains then as their int8 ranges allow).
    """
    floor = np.minimum(state_limit, MIN_GAIN)
    if shifts is None:
        shifts = [_shift_for(float(np.max(floor * wm)) if wm.size else 0.0) for wm in weight_max]
    shifts = [int(s) for s in shifts]
    gains = state_limit.astype(np.float64).copy()
    for s, wm in zip(shifts, weight_max):
        with np.errstate(divide="ignore"):
            gains = np.minimum(gains, np.where(wm > 0, WEIGHT_MAX * 2.0 ** s / np.maximum(wm, 1e-300), np.inf))
    return np.maximum(gains, 1.0), shifts


def to_int(c: np.ndarray, step: np.ndarray, hessian: np.ndarray | None) -> np.ndarray:
    """Integers for coefficients ``c`` on grids ``step``: nearest, or with error feedback under ``hessian``."""
    if hessian is None:
        return np.clip(np.round(c / step), WEIGHT_MIN, WEIGHT_MAX).astype(np.int64)
    return round_with_feedback(hessian, c, step, WEIGHT_MIN, WEIGHT_MAX)


def saturating_int16(x) -> np.ndarray:
    return np.clip(np.round(np.asarray(x, np.float64)), -STATE_MAX - 1, STATE_MAX).astype(np.int64)


READOUT_COPY = "readout copy"    # hidden neurons that repeat the readout's spikes one step later (``_copy_readout``)
COPY_WEIGHT = 64                 # int8: the readout -> copy and readout -> output weight; half of it cancels


def _copy_readout(spec: dict, readout: HiddenFloat, starts: dict[str, int], s_rec: int, n: int) -> dict[str, Any]:
    """Output neurons that fire exactly when the readout's hidden neuron fired the step before.

    A synapse with dash 1 keeps half its current: a spike's weight w leaves w/2, w/4, ... behind. A copy
    neuron C (memoryless, dash_syn 1) takes the readout R's spike with weight w and its own with -w/2: by
    induction its current after the decay is (w/2) R[t-1] exactly (w a power of two), so C fires at threshold
    w/2 iff R fired the step before: C[t] = R[t-1]. The output neuron O (dash_syn_out 1, dash_mem_out 0: V is
    its current) takes R with w and C with -w/2: its current is (w/2) R[t-1], so O[t] = R[t-1] exactly, one
    spike at most."""
    r0, c0, m = starts[readout.name], starts[READOUT_COPY], readout.n
    for j in range(m):
        spec["weights_rec"][r0 + j, c0 + j, 0] = COPY_WEIGHT
        spec["weights_rec"][c0 + j, c0 + j, 0] = -COPY_WEIGHT // 2
    sl = slice(c0, c0 + m)
    spec["dash_syn"][sl] = spec["dash_syn_2"][sl] = 1
    spec["dash_mem"][sl] = 0
    spec["threshold"][sl] = (COPY_WEIGHT // 2) << s_rec
    spec["bias"][sl] = 0
    w_out = np.zeros((n, m), np.int8)
    for j in range(m):
        w_out[r0 + j, j] = COPY_WEIGHT
        w_out[c0 + j, j] = -COPY_WEIGHT // 2
    return {"weights_out": w_out, "weight_shift_out": 0, "dash_syn_out": np.ones(m, np.uint8),
            "dash_mem_out": np.zeros(m, np.uint8), "threshold_out": np.full(m, COPY_WEIGHT // 2, np.int16),
            "bias_out": np.zeros(m, np.int16), "aliases": [[] for _ in range(n)]}


def _place_relay(spec: dict, r: relay_rules.Relay, starts: dict[str, int], from_input: bool, shift: int) -> None:
    """A source's relays: relay j takes channel j of ``r.source`` on its first synapse (the input matrix or the
    recurrent one, whose left ``shift`` it is), integrates (dash_mem 15) and fires at its threshold."""
    r0 = starts[r.name]
    w8, theta = r.registers(shift)
    for j in range(r.n):
        if from_input:
            spec["weights_in"][j, r0 + j, 0] = w8
        else:
            spec["weights_rec"][starts[r.source] + j, r0 + j, 0] = w8
    sl = slice(r0, r0 + r.n)
    spec["dash_syn"][sl] = spec["dash_syn_2"][sl] = r.dash
    spec["dash_mem"][sl] = relay_rules.RELAY_DASH_MEM
    spec["threshold"][sl] = theta
    spec["bias"][sl] = 0


def _spread(v: np.ndarray) -> dict[str, float]:
    return {"min": float(np.min(v)), "median": float(np.median(v)), "max": float(np.max(v))}
