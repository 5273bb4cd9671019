"""A population in Xylo's form before gains and rounding (float, IR voltage units): how each rule places it.

Two ways to place a hidden population (per rule; ``lower.py`` measures which agrees best):

* ``direct`` -- one chip neuron per IR neuron, as Rockpool maps it: dash_syn ~ alpha, dash_mem ~ beta
  (nearest on the grid), weights g W / a (the chip adds input before it decays: i <- a (i + w s)),
  threshold g theta. The chip then fires up to 31 spikes per step where the IR fires one
  (the deployed graph says so: ``max_spikes`` 31, ``fire_test`` ">=").
* ``single`` -- a memoryless readout (dash_mem 0: V = i_1 + i_2 + bias, recomputed every step) over
  two synaptic currents that carry the neuron's memory (``decays.py``): the IR's voltage kernel as
  two exponentials, its subtract reset fed back through the neuron's own recurrent weights. The
  bias holds an offset ``off`` and the threshold is g theta + off >= 2^14, so V (16 bits) can never
  reach two thresholds: one spike per step at most, exactly the IR's rule, while the currents keep
  the full range below threshold. Weights come from the kernel fit, or from ``regression.py``.

The readout population runs on the output neurons (one synapse, their own membrane, one spike per
step: the IR's rule): nearest dashes with a gain that matches the kernels, or identified weights.
Gains, shifts and rounding to integers: ``integers.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.lowering import decays

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
    d_syn = decays.nearest_dash(alpha)
    d_mem = decays.nearest_dash(beta)
    a = decays.grid(d_syn)
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
        fit = decays.two_exponential(pair[0], pair[1], dashes)
        sel = (alpha == pair[0]) & (beta == pair[1])
        u[:, sel] = np.array(fit.u)[:, None]
        rho[:, sel] = np.array(fit.rho)[:, None]
    w = {src: u[:, :, None] * m[None] for src, m in sources.items()}
    w[name] = w.get(name, np.zeros((2, n, n))) + np.stack([np.diag(rho[k] * theta) for k in range(2)])
    register = np.zeros(n)
    if np.any(bias_v) or np.any(bias_i):
        a = decays.grid(np.asarray(dashes))
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
        d_syn, d_mem = decays.nearest_dash(alpha), decays.nearest_dash(beta)
    else:
        d_syn, d_mem = np.full(theta.size, dashes[0]), np.full(theta.size, dashes[1])
    a, b = decays.grid(d_syn), decays.grid(d_mem)
    if np.any(a == 0):
        raise SnnccError("an output synaptic decay of 0 clears the current before it reaches the membrane",
                         field=f"node '{name}'.tau_syn")
    n_k = np.arange(decays.HORIZON)
    lam = decays.FIT_WEIGHT ** n_k
    gain = np.empty(theta.size)
    for j in range(theta.size):
        chip = a[j] * decays.lif_kernel(a[j], b[j], n_k) * lam
        ir = decays.lif_kernel(alpha[j], beta[j], n_k) * lam
        gain[j] = float(chip @ ir / (chip @ chip))
    w = gain[:, None] * weight
    if bias_source and np.any(bias_i):
        return OutputFloat(name, source, theta, d_syn, d_mem, np.concatenate([w, (bias_i / a)[:, None]], 1),
                           np.asarray(bias_v, np.float64), bias_source=True)
    return OutputFloat(name, source, theta, d_syn, d_mem, w, bias_v + bias_i / np.maximum(1 - alpha, 1e-12))
