"""Xylo's integer parameters for each population of a chain (weights, shifts, dashes, thresholds, biases).

Two ways to place a hidden population (per rule; ``lowering.py`` measures which agrees best):

* ``direct`` -- one chip neuron per IR neuron, as Rockpool maps it: dash_syn ~ alpha, dash_mem ~ beta
  (nearest on the grid), weights g W / a (the chip adds input before it decays: i <- a (i + w s)),
  threshold g theta. The chip then fires up to 31 spikes per step where the IR fires one
  (the deployed graph says so: ``max_spikes`` 31, ``fire_test`` ">=").
* ``single`` -- a memoryless readout (dash_mem 0: V = i_1 + i_2 + bias, recomputed every step) over
  two synaptic currents that carry the neuron's memory (``kernels.py``): the IR's voltage kernel as
  two exponentials, its subtract reset fed back through the neuron's own recurrent weights. The
  bias holds an offset ``off`` and the threshold is g theta + off >= 2^14, so V (16 bits) can never
  reach two thresholds: one spike per step at most, exactly the IR's rule, while the currents keep
  the full range below threshold. Weights come from the kernel fit, or from ``identify.py``.

The readout population runs on the output neurons (one synapse, their own membrane, one spike per
step: the IR's rule): nearest dashes with a gain that matches the kernels, or identified weights.
Gains are per neuron (the threshold is per neuron); a weight matrix shares one left shift; rounding
is to nearest or with error feedback (``snncc/rounding.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snncc.errors import SnnccError
from snncc.rounding import round_with_feedback
from snncc.targets.xylo import identify, kernels
from snncc.targets.xylo.chip import CORE

STATE_MAX = CORE.state_max
WEIGHT_MAX, WEIGHT_MIN = CORE.weight_max, CORE.weight_min
SAFE_WEIGHT_SHIFT = 8             # the largest left shift under which no int8 weight wraps in int16

SINGLE_THRESHOLD = 2 ** 14 + 1    # 2 * 16385 > 32767: a 16-bit V cannot hold two thresholds
BIAS_SOURCE = "bias source"       # an always-on hidden neuron (one spike every step) that carries biases
STATE_MARGIN = 1.25               # headroom over the largest calibration state
MIN_GAIN = 64.0                   # chip units per threshold the shift choice tries to keep (state resolution)
MAX_GAIN = 4096.0


@dataclass
class HiddenFloat:
    """A hidden population in chip form, IR voltage units (threshold ``theta``), before gains and rounding."""

    name: str
    method: str                                 # "single" | "direct"
    theta: np.ndarray                           # (n,)
    dash_syn: np.ndarray                        # (n, 2)
    dash_mem: np.ndarray                        # (n,)
    weights: dict[str, np.ndarray]              # source -> (2, n, n_src); own name: recurrence (+ reset feedback)
    bias: np.ndarray                            # (n,) added to V every step
    fit: str = "kernel"
    hessians: list[np.ndarray] | None = None    # per neuron, over the columns of ``columns``
    columns: list[tuple[str, int]] = field(default_factory=list)   # (source, synapse) blocks, in feature order

    @property
    def n(self) -> int:
        return int(self.theta.size)


@dataclass
class OutputFloat:
    name: str
    source: str
    theta: np.ndarray
    dash_syn: np.ndarray                        # (n,)
    dash_mem: np.ndarray
    weight: np.ndarray                          # (n, n_src [+ 1]) chip form: j <- a (j + w s); last column: the
    bias: np.ndarray                            # bias source's weight when ``bias_source`` (then ``bias`` is b_V)
    fit: str = "kernel"
    hessians: list[np.ndarray] | None = None
    bias_source: bool = False

    @property
    def n(self) -> int:
        return int(self.theta.size)


# -- float chip form ---------------------------------------------------------------------------

def steady_bias(alpha, beta, bias_v, bias_i) -> np.ndarray:
    """The constant voltage a LIF's biases settle to: b_V / (1 - beta) + b_I / ((1 - alpha)(1 - beta))."""
    return bias_v / np.maximum(1 - beta, 1e-12) + bias_i / np.maximum((1 - alpha) * (1 - beta), 1e-12)


def hidden_direct(name: str, alpha, beta, theta, sources: dict[str, np.ndarray], bias_v, bias_i) -> HiddenFloat:
    """One chip neuron per IR neuron: nearest dashes; the chip's order i <- a (i + w s) gives w = W / a."""
    d_syn = kernels.nearest_dash(alpha)
    d_mem = kernels.nearest_dash(beta)
    a = kernels.grid(d_syn)
    n = theta.size
    if np.any(a == 0):
        raise SnnccError("a synaptic decay of 0 (alpha < 1/4) clears Xylo's current before it reaches the membrane; "
                         "the direct rule cannot place it (use the single rule)", field=f"node '{name}'.tau_syn")
    w = {src: np.stack([m / a[:, None], np.zeros_like(m)]) for src, m in sources.items()}
    # a current bias settles to b_I / (1 - alpha) in the current: a constant voltage bias of that size
    bias = bias_v + bias_i / np.maximum(1 - alpha, 1e-12)
    return HiddenFloat(name, "direct", theta, np.stack([d_syn, d_syn], 1), d_mem, w, bias)


def hidden_single(name: str, alpha, beta, theta, sources: dict[str, np.ndarray], dashes: tuple[int, int],
                  bias_v, bias_i, bias_lag: int | None = 1) -> HiddenFloat:
    """Memoryless readout over two currents fitted to the IR kernel (per distinct (alpha, beta) pair).

    Biases: the IR adds b_I to the current and b_V to the voltage every step from step 0, so V gains
    b_I h(n) + b_V beta^n at step n. The bias register carries the step-0 term (b_I + b_V) and an always-on
    source neuron, whose spikes reach the population from IR step ``bias_lag`` = 1 on, the rest through the
    same kernel fits (w_k = b_I u_k a_k - b_V rho_k). With ``bias_lag`` 0 (the population runs one step
    late) the source covers step 0 too and the register stays 0; otherwise (None) the register holds
    the constant the biases settle to and the first steps differ."""
    n = theta.size
    u = np.zeros((2, n))
    rho = np.zeros((2, n))
    for pair in {(float(x), float(y)) for x, y in zip(alpha, beta)}:
        fit = kernels.two_exponential(pair[0], pair[1], dashes)
        sel = (alpha == pair[0]) & (beta == pair[1])
        u[:, sel] = np.array(fit.u)[:, None]
        rho[:, sel] = np.array(fit.rho)[:, None]
    w = {src: u[:, :, None] * m[None] for src, m in sources.items()}
    w[name] = w.get(name, np.zeros((2, n, n))) + np.stack([np.diag(rho[k] * theta) for k in range(2)])
    register = np.zeros(n)
    if np.any(bias_v) or np.any(bias_i):
        a = kernels.grid(np.asarray(dashes))
        if bias_lag == 1:
            register = bias_i + bias_v
            w[BIAS_SOURCE] = np.stack([bias_i * u[k] * a[k] - bias_v * rho[k] for k in range(2)])[:, :, None]
        elif bias_lag == 0:
            w[BIAS_SOURCE] = np.stack([bias_i * u[k] - bias_v * rho[k] / beta for k in range(2)])[:, :, None]
        else:
            register = steady_bias(alpha, beta, bias_v, bias_i)
    return HiddenFloat(name, "single", theta, np.tile(np.asarray(dashes), (n, 1)), np.zeros(n, np.int64), w,
                       register, columns=[(s, k) for k in range(2) for s in w])


def output_native(name: str, source: str, alpha, beta, theta, weight: np.ndarray, bias_v, bias_i,
                  dashes: tuple[int, int] | None = None, bias_source: bool = False) -> OutputFloat:
    """Output neurons (one synapse, a membrane): dashes nearest (or given); the weight gain that best matches
    the IR's voltage kernel h_{alpha,beta} with the chip's a * h_{a,b} (weighted least squares). A voltage
    bias is the output neuron's own register (exact); a current bias comes from the always-on source when
    ``bias_source`` (its spikes reach the output from the population's IR step 0: w = b_I / a), else as the
    constant voltage it settles to."""
    if dashes is None:
        d_syn, d_mem = kernels.nearest_dash(alpha), kernels.nearest_dash(beta)
    else:
        d_syn, d_mem = np.full(theta.size, dashes[0]), np.full(theta.size, dashes[1])
    a, b = kernels.grid(d_syn), kernels.grid(d_mem)
    if np.any(a == 0):
        raise SnnccError("an output synaptic decay of 0 clears the current before it reaches the membrane",
                         field=f"node '{name}'.tau_syn")
    n_k = np.arange(kernels.HORIZON)
    lam = kernels.FIT_WEIGHT ** n_k
    gain = np.empty(theta.size)
    for j in range(theta.size):
        chip = a[j] * kernels.lif_kernel(a[j], b[j], n_k) * lam
        ir = kernels.lif_kernel(alpha[j], beta[j], n_k) * lam
        gain[j] = float(chip @ ir / (chip @ chip))
    w = gain[:, None] * weight
    if bias_source and np.any(bias_i):
        return OutputFloat(name, source, theta, d_syn, d_mem, np.concatenate([w, (bias_i / a)[:, None]], 1),
                           np.asarray(bias_v, np.float64), bias_source=True)
    return OutputFloat(name, source, theta, d_syn, d_mem, w, bias_v + bias_i / np.maximum(1 - alpha, 1e-12))


# -- identification ------------------------------------------------------------------------------

def identify_hidden(pop: HiddenFloat, trains: dict[str, np.ndarray], v_pre: np.ndarray, scale: float,
                    ridge: float) -> HiddenFloat:
    """Refit a ``single`` population's weights to the float graph's voltages (``identify.py``);
    ``trains``: source -> spike trains already delayed as the IR delivers them (own: delayed 1)."""
    decays = tuple(float(v) for v in kernels.grid(pop.dash_syn[0]))
    names = [s for s, k in pop.columns if k == 0]
    constant = bool(np.any(pop.bias != 0))
    d = identify.design([trains[s] for s in names], decays, v_pre, pop.theta, scale, constant)
    sizes = [trains[s].shape[2] for s in names]
    new = {s: np.zeros_like(m) for s, m in pop.weights.items()}
    bias = pop.bias.copy()
    hessians = []
    for j, (h, rhs) in enumerate(identify.normal_equations(d, range(pop.n))):
        prior = np.concatenate([pop.weights[s][k, j] for k in range(2) for s in names]
                               + ([pop.bias[j:j + 1]] if constant else []))
        c, hr = identify.ridge_towards(h, rhs, prior, ridge)
        hessians.append(hr)
        at = 0
        for k in range(2):
            for s, size in zip(names, sizes):
                new[s][k, j] = c[at:at + size]
                at += size
        if constant:
            bias[j] = c[at]
    return HiddenFloat(pop.name, pop.method, pop.theta, pop.dash_syn, pop.dash_mem, new, bias, fit="identified",
                       hessians=hessians, columns=pop.columns)


def hidden_hessians(pop: HiddenFloat, trains: dict[str, np.ndarray], v_pre: np.ndarray, scale: float,
                    ridge: float) -> HiddenFloat:
    """Only the quadratic forms (for rounding with error feedback), keeping the kernel-fit weights."""
    decays = tuple(float(v) for v in kernels.grid(pop.dash_syn[0]))
    names = [s for s, k in pop.columns if k == 0]
    constant = bool(np.any(pop.bias != 0))
    d = identify.design([trains[s] for s in names], decays, v_pre, pop.theta, scale, constant)
    hs = []
    for h, _ in identify.normal_equations(d, range(pop.n)):
        hs.append(h + ridge * max(float(np.trace(h)) / len(h), 1e-12) * np.eye(len(h)))
    pop.hessians = hs
    return pop


def identify_output(out: OutputFloat, pre: np.ndarray, own: np.ndarray, v_pre: np.ndarray, scale: float,
                    ridge: float) -> OutputFloat:
    """Refit output weights: V_pre + theta sum_{m<t} b^(t-m) s[m] (the chip's own reset, moved to the target;
    the voltage-bias register's part taken out) ~ membrane-filtered synaptic traces of the presynaptic spikes
    (``pre`` delayed as the IR delivers them; with ``bias_source``, its last column is the source's train)."""
    n = out.n
    new = out.weight.copy()
    hs = []
    for dash_pair in {(int(a), int(b)) for a, b in zip(out.dash_syn, out.dash_mem)}:
        a, b = (float(v) for v in kernels.grid(np.asarray(dash_pair)))
        current = identify.chip_filter(pre.astype(np.float64), a)
        feat = _membrane(current, b)
        sel = np.flatnonzero((out.dash_syn == dash_pair[0]) & (out.dash_mem == dash_pair[1]))
        reset = _membrane(identify.delayed(own.astype(np.float64), 1), b) * b   # sum_{m<t} b^(t-m) s[m]
        register = _membrane(np.ones(v_pre.shape[:2] + (1,)), b) * out.bias[None, None, :]   # the fixed b_V part
        target = v_pre + out.theta[None, None, :] * reset - register
        d = identify.Design(feat.reshape(-1, feat.shape[2]), target.reshape(-1, n),
                            np.exp(-np.abs(v_pre.reshape(-1, n) - out.theta) / (scale * out.theta)))
        for j, (h, rhs) in zip(sel, identify.normal_equations(d, sel)):
            c, hr = identify.ridge_towards(h, rhs, out.weight[j], ridge)
            new[j] = c
            hs.append((j, hr))
    hessians = [h for _, h in sorted(hs, key=lambda p: p[0])]
    return OutputFloat(out.name, out.source, out.theta, out.dash_syn, out.dash_mem, new, out.bias, "identified", hessians,
                       out.bias_source)


def _membrane(z: np.ndarray, b: float) -> np.ndarray:
    """G[t] = b G[t-1] + z[t] along axis 1."""
    out = np.empty_like(z)
    acc = np.zeros((z.shape[0], z.shape[2]))
    for t in range(z.shape[1]):
        acc = b * acc + z[:, t]
        out[:, t] = acc
    return out


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
