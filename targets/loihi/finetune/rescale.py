"""Fine-tuning starting points for Loihi: each neuron its own scale, weights rounded with error compensation.

A neuron's spikes do not change when its incoming weights, bias and threshold are multiplied by one
factor s_i > 0 (its equations are linear in them; spikes are 0/1). The per-layer rule gives every neuron
of a layer the weight step of the layer's largest weight, s = floor(256 / max|W into the layer|); here
each neuron takes the largest scale its own incoming weights allow, at the exponents the rule chose
(so the format is kept: wgtExp stays what it was, 0 where netx runs it):

    s_i       = 254 / max_j (|W_ij| / 2**e_j)       e_j: the exponent of synapse j's projection
    vThMant_i = round(theta_i * s_i)

A threshold lives in a profile, 8 per core, so the neurons of a layer share at most 8 scales (7 where the
layer also holds always-on bias sources, whose threshold stays theirs): ``scale_groups`` groups them by
max|W_i| losing the fewest bits, and the cores a network needs do not grow. Weights are then rounded
with error feedback (``snncc/rounding.py``) on the grid of even mantissas, H being the second moments
of the neuron's presynaptic signals as its membrane sees them: the float teacher's spikes (inputs, the
previous population, its own population one step late, the always-on sources of its current biases)
filtered by the neuron's chip decays,
z = (1 - beta q^-1)^-1 (1 - alpha q^-1)^-1 pre. Label-free: only the teacher's spikes on the inputs
given. Measured on braille_zero_2023 (per-layer, 1,000 held-out random inputs, bench/studies/loihi_precision.py):
0.846 as lowered, 0.889 with a scale per neuron, 0.903 with error-feedback rounding too, 0.896 with at most
8 scales per layer; ``fine`` 0.920 (docs/finetune.md).
"""

from __future__ import annotations

import copy

import numpy as np

from snncc.targets.kit.graphs import current_biases
from snncc.targets.kit.compute import damped, round_with_feedback
from snncc.targets.loihi import chip

DAMPING = 0.1     # H + 0.1 mean(diag H) I (braille_zero: 0.01 / 0.1 / 0.3 within 0.005 of each other)
CHUNK = 64        # calibration samples filtered at a time


def _filtered(pre: np.ndarray, alpha: float, beta: float) -> np.ndarray:
    """pre (N, T, k) through the CUBA kernel: u = alpha u + pre, v = beta v + u (float64)."""
    from scipy.signal import lfilter

    z = lfilter([1.0], [1.0, -alpha], np.asarray(pre, np.float64), axis=1)
    return lfilter([1.0], [1.0, -beta], z, axis=1)


def presynaptic(lowered, layer: int, x: np.ndarray, spikes: dict[str, np.ndarray]) -> np.ndarray:
    """The presynaptic signals of ``lowered.layers[layer]`` in the column order of its incoming weights
    (feed-forward, one column per current-bias term, recurrent): (N, T, k) float64."""
    c = lowered.layers[layer]
    pre = x if layer == 0 else spikes[lowered.layers[layer - 1].lif]
    parts = [np.asarray(pre, np.float64)]
    for t in current_biases(lowered.order, c.lif):
        on = np.zeros(pre.shape[:2] + (1,))
        on[:, t.start:] = 1.0
        parts.append(on)
    if c.rec:
        own = np.asarray(spikes[c.lif], np.float64)
        parts.append(np.concatenate([np.zeros_like(own[:, :1]), own[:, :-1]], axis=1))
    return np.concatenate(parts, axis=2)


def kernel_moments(lowered, layer: int, x: np.ndarray, spikes: dict[str, np.ndarray], alpha: float,
                   beta: float) -> np.ndarray:
    """H = E[z z^T] of the layer's presynaptic signals through the CUBA kernel, ``CHUNK`` samples at a time."""
    h, rows = 0.0, 0
    for start in range(0, x.shape[0], CHUNK):
        part = slice(start, start + CHUNK)
        z = _filtered(presynaptic(lowered, layer, x[part], {p: v[part] for p, v in spikes.items()}), alpha, beta)
        z = z.reshape(-1, z.shape[-1])
        h = h + z.T @ z
        rows += z.shape[0]
    return h / max(rows, 1)


def scale_groups(top: np.ndarray, groups: int) -> np.ndarray:
    """Each neuron's shared row maximum when the neurons form at most ``groups`` groups of one scale each:
    contiguous in sorted max|W_i|, chosen to lose the fewest bits, sum_i log2(max of i's group / max|W_i|)
    (dynamic programming; a group takes its largest member's scale, so no weight leaves the range)."""
    top = np.asarray(top, np.float64)
    live = top > 0
    out = top.copy()
    if np.count_nonzero(live) <= groups:
        return out
    idx = np.flatnonzero(live)[np.argsort(top[live], kind="stable")]
    logs = np.log2(top[idx])
    n = logs.size
    csum = np.concatenate([[0.0], np.cumsum(logs)])
    cost = np.full((groups + 1, n + 1), np.inf)
    cost[0, 0] = 0.0
    cut = np.zeros((groups + 1, n + 1), np.int64)
    for g in range(1, groups + 1):
        for b in range(1, n + 1):
            a = np.arange(b)
            total = cost[g - 1, a] + (b - a) * logs[b - 1] - (csum[b] - csum[a])
            cut[g, b] = int(np.argmin(total))
            cost[g, b] = total[cut[g, b]]
    g, b = groups, n
    while b > 0:
        a = cut[g, b]
        out[idx[a:b]] = top[idx[b - 1]]
        b, g = a, g - 1
    return out


def float_rows(lowered, layer: int) -> tuple[np.ndarray, int, int]:
    """The float incoming weights of a layer's model neurons in ``presynaptic``'s column order, with
    the number of feed-forward columns and of bias terms."""
    c = lowered.layers[layer]
    order = lowered.order
    w = order.node(c.ff).weight
    terms = current_biases(order, c.lif)
    parts = [w] + [t.vector.reshape(-1, 1) for t in terms]
    if c.rec:
        parts.append(order.node(c.rec).weight)
    return np.concatenate(parts, axis=1), w.shape[1], len(terms)


def rescaled(lowered, network, x: np.ndarray, spikes: dict[str, np.ndarray], *, per_neuron: bool = True,
             moments: dict | None = None):
    """``network`` with every layer's model-neuron weights requantized from the float graph by compensated
    rounding, at per-neuron scales (``per_neuron``) or at the rule's layer scales; thresholds follow the
    scales, and so does a voltage bias. ``spikes``: the teacher's spikes per population on inputs ``x``;
    ``moments``: a dict that keeps the second moments between calls on the same inputs.
    A new network; None when a layer's format does not allow it (per-synapse exponents, a register out
    of range)."""
    net = copy.deepcopy(network)
    cache = {} if moments is None else moments
    layer_scale = {lq.lif: float(lq.scale) for lq in lowered.quant_record.layers}
    for k, (c, lay) in enumerate(zip(lowered.layers, net.layers[1:])):
        op = lowered.order.node(c.lif)
        if np.ndim(lay.wgt_exp) or (c.rec and np.ndim(lay.wgt_exp_rec)):
            return None
        m = lay.model_n
        w, n_in, n_terms = float_rows(lowered, k)
        exps = np.full(w.shape[1], float(lay.wgt_exp))
        if c.rec:
            exps[n_in + n_terms:] = float(lay.wgt_exp_rec)
        target = w / 2.0 ** exps[None, :]               # mantissa per unit scale
        top = np.max(np.abs(target), axis=1)
        theta = np.broadcast_to(np.asarray(op.threshold, np.float64), (m,))
        if per_neuron:
            # thresholds live in profiles (8 per core): at most that many scales, one kept for the sources
            top = scale_groups(top, chip.VTH_PROFILES_PER_CORE - (1 if lay.always_on else 0))
            s = np.where(top > 0, chip.WEIGHT_MAX / np.where(top > 0, top, 1.0), layer_scale[c.lif])
            s = np.minimum(s, (chip.V_TH_MANT_MAX - 0.5) / theta)
        else:
            s = np.full(m, layer_scale[c.lif])
        vth = np.round(theta * s)
        if np.any(vth < chip.V_TH_MANT_MIN):
            return None
        if op.bias is not None and op.bias_placement == "voltage":
            bias = np.asarray(lay.bias, np.int64).copy()
            bias[:m] = np.round(op.bias * s * 2.0 ** (chip.V_TH_SHIFT - lay.bias_exp))
            if np.any(np.abs(bias[:m]) > chip.BIAS_MANT_MAX):
                return None
            lay.bias = bias
        rows = np.zeros((m, w.shape[1]))
        i_dec = np.broadcast_to(np.asarray(lay.i_decay, np.int64), (lay.n,))[:m]
        v_dec = np.broadcast_to(np.asarray(lay.v_decay, np.int64), (lay.n,))[:m]
        for a, b in sorted(set(zip(i_dec.tolist(), v_dec.tolist()))):
            sel = (i_dec == a) & (v_dec == b)
            if (k, a, b) not in cache:
                cache[(k, a, b)] = damped(kernel_moments(lowered, k, x, spikes, 1.0 - a / chip.DECAY_ONE,
                                                         1.0 - b / chip.DECAY_ONE), DAMPING)
            h = cache[(k, a, b)]
            # symmetric, -254..254: never the -256 that Lava's inhibitory format cannot hold (portability.py)
            rows[sel] = 2 * round_with_feedback(h, target[sel] * s[sel, None], 2.0, -(chip.WEIGHT_MAX // 2),
                                                chip.WEIGHT_MAX // 2)
        full = np.asarray(lay.weight).copy()
        full[:m, :n_in] = rows[:, :n_in]
        repeats = (full.shape[1] - n_in) // n_terms if n_terms else 0
        for j in range(n_terms):
            full[:m, n_in + j * repeats:n_in + (j + 1) * repeats] = rows[:, n_in + j:n_in + j + 1]
        lay.weight = full.astype(np.asarray(lay.weight).dtype)
        if c.rec:
            rec = np.asarray(lay.weight_rec).copy()
            rec[:m, :m] = rows[:, n_in + n_terms:]
            lay.weight_rec = rec.astype(np.asarray(lay.weight_rec).dtype)
        regs = np.broadcast_to(np.asarray(lay.v_th_mant, np.int64), (lay.n,)).copy()
        regs[:m] = vth.astype(np.int64)
        lay.v_th_mant = int(regs[0]) if np.all(regs == regs[0]) else regs
    return net
