"""Fit a memoryless-readout population's synaptic weights to the float graph's own voltages.

Calibration: the float graph runs on calibration inputs; for a population P its pre-reset
voltage V_j[t] (the IR's, subtract reset: V_post + theta * s) is regressed, per neuron j, on the
presynaptic spike trains as Xylo's synapses filter them (chip order, decay a_k of synapse k):

    F_k(z)[t] = a_k (F_k(z)[t-1] + z[t]),   z = pre spikes delayed by the IR delay, or P's own spikes
                                            delayed by 1 (recurrence and the reset's feedback)
    V_j[t] ~ sum_k F_k(pre)[t] . c_jk + F_k(own)[t] . r_jk (+ b_j)

teacher-forced (the float graph's spikes drive every feature) and weighted by
exp(-|V - theta| / (scale theta)): the voltages that decide a spike count most. The solution is a
ridge regression towards the kernel fit (``decays.two_exponential``), so features the inputs never
exercise keep the kernel's value. ``round_with_feedback`` (``kit.compute``) then rounds one weight
at a time and moves the weights not yet rounded to absorb the error under the same quadratic form,
so rounding costs as little voltage error as the data allow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.xylo.lowering.decays import grid
from snncc.targets.xylo.lowering.chip_form import HiddenFloat, OutputFloat

ROW_FLOOR = 1e-2          # rows whose regression weight is below this are left out (they hardly count)
ROW_BLOCK = 2048          # rows per block of normal_equations (a block of features stays in cache)


def chip_filter(z: np.ndarray, a: float) -> np.ndarray:
    """F[t] = a (F[t-1] + z[t]) along axis 1 of (B, T, n)."""
    out = np.empty_like(z, dtype=np.float64)
    acc = np.zeros((z.shape[0], z.shape[2]))
    for t in range(z.shape[1]):
        acc = a * (acc + z[:, t])
        out[:, t] = acc
    return out


def delayed(z: np.ndarray, d: int) -> np.ndarray:
    """z[:, t - d] (zeros before)."""
    if d == 0:
        return z
    out = np.zeros_like(z)
    if d < z.shape[1]:
        out[:, d:] = z[:, :-d]
    return out


@dataclass
class Design:
    """Regression data of one population: features (rows, F) and, per neuron, its targets and row weights."""

    features: np.ndarray      # (rows, F)
    target: np.ndarray        # (rows, n) pre-reset voltages
    weight: np.ndarray        # (rows, n)


def design(sources: list[np.ndarray], decays: tuple[float, float], v_pre: np.ndarray, theta: np.ndarray,
           scale: float, constant: bool) -> Design:
    """Features: for each synapse k, each source's filtered trains (already delayed), then a constant column."""
    cols = [chip_filter(src.astype(np.float64), a) for a in decays for src in sources]
    if constant:
        cols.append(np.ones(v_pre.shape[:2] + (1,)))
    f = np.concatenate(cols, axis=2).reshape(-1, sum(c.shape[2] for c in cols))
    y = v_pre.reshape(-1, v_pre.shape[2])
    w = np.exp(-np.abs(y - theta[None, :]) / (scale * theta[None, :]))
    return Design(f, y, w)


def normal_equations(d: Design, neurons) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per neuron j of ``neurons``: (H, b) = (A^T A, A^T y) of its weighted rows, A = w_j * features on the rows
    with w_j >= ROW_FLOOR. Summed over blocks of ROW_BLOCK rows, each block used by every neuron while it is in
    cache (the features are read once, not once per neuron)."""
    neurons = [int(j) for j in neurons]
    f_count = d.features.shape[1]
    h = np.zeros((len(neurons), f_count, f_count))
    b = np.zeros((len(neurons), f_count))
    for start in range(0, d.features.shape[0], ROW_BLOCK):
        rows = slice(start, start + ROW_BLOCK)
        block, weight, target = d.features[rows], d.weight[rows], d.target[rows]
        for at, j in enumerate(neurons):
            w = weight[:, j]
            keep = w >= ROW_FLOOR
            if not keep.any():
                continue
            a = block[keep] * w[keep, None]
            h[at] += a.T @ a
            b[at] += a.T @ (target[keep, j] * w[keep])
    return list(zip(h, b))


def ridge_towards(h: np.ndarray, b: np.ndarray, prior: np.ndarray, ridge: float) -> tuple[np.ndarray, np.ndarray]:
    """argmin |A c - y|^2 + lam |c - prior|^2, lam = ridge * mean(diag H); returns (c, H + lam I)."""
    lam = ridge * max(float(np.trace(h)) / max(len(b), 1), 1e-12)
    hr = h + lam * np.eye(len(b))
    return prior + np.linalg.solve(hr, b - h @ prior), hr


# -- a population's fit ---------------------------------------------------------------------------

def fitted_hidden(pop: HiddenFloat, trains: dict[str, np.ndarray], v_pre: np.ndarray, scale: float,
                    ridge: float) -> HiddenFloat:
    """Refit a ``single`` population's weights to the float graph's voltages (the module doc);
    ``trains``: source -> spike trains already delayed as the IR delivers them (own: delayed 1)."""
    rates = tuple(float(v) for v in grid(pop.dash_syn[0]))
    names = [s for s, k in pop.columns if k == 0]
    constant = bool(np.any(pop.bias != 0))
    d = design([trains[s] for s in names], rates, v_pre, pop.theta, scale, constant)
    sizes = [trains[s].shape[2] for s in names]
    new = {s: np.zeros_like(m) for s, m in pop.weights.items()}
    bias = pop.bias.copy()
    hessians = []
    for j, (h, rhs) in enumerate(normal_equations(d, range(pop.n))):
        prior = np.concatenate([pop.weights[s][k, j] for k in range(2) for s in names]
                               + ([pop.bias[j:j + 1]] if constant else []))
        c, hr = ridge_towards(h, rhs, prior, ridge)
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
    rates = tuple(float(v) for v in grid(pop.dash_syn[0]))
    names = [s for s, k in pop.columns if k == 0]
    constant = bool(np.any(pop.bias != 0))
    d = design([trains[s] for s in names], rates, v_pre, pop.theta, scale, constant)
    hs = []
    for h, _ in normal_equations(d, range(pop.n)):
        hs.append(h + ridge * max(float(np.trace(h)) / len(h), 1e-12) * np.eye(len(h)))
    pop.hessians = hs
    return pop


def fitted_output(out: OutputFloat, pre: np.ndarray, own: np.ndarray, v_pre: np.ndarray, scale: float,
                    ridge: float) -> OutputFloat:
    """Refit output weights: V_pre + theta sum_{m<t} b^(t-m) s[m] (the chip's own reset, moved to the target;
    the voltage-bias register's part taken out) ~ membrane-filtered synaptic traces of the presynaptic spikes
    (``pre`` delayed as the IR delivers them; with ``bias_source``, its last column is the source's train)."""
    n = out.n
    new = out.weight.copy()
    hs = []
    for dash_pair in {(int(a), int(b)) for a, b in zip(out.dash_syn, out.dash_mem)}:
        a, b = (float(v) for v in grid(np.asarray(dash_pair)))
        current = chip_filter(pre.astype(np.float64), a)
        feat = _membrane(current, b)
        sel = np.flatnonzero((out.dash_syn == dash_pair[0]) & (out.dash_mem == dash_pair[1]))
        reset = _membrane(delayed(own.astype(np.float64), 1), b) * b   # sum_{m<t} b^(t-m) s[m]
        register = _membrane(np.ones(v_pre.shape[:2] + (1,)), b) * out.bias[None, None, :]   # the fixed b_V part
        target = v_pre + out.theta[None, None, :] * reset - register
        d = Design(feat.reshape(-1, feat.shape[2]), target.reshape(-1, n),
                            np.exp(-np.abs(v_pre.reshape(-1, n) - out.theta) / (scale * out.theta)))
        for j, (h, rhs) in zip(sel, normal_equations(d, sel)):
            c, hr = ridge_towards(h, rhs, out.weight[j], ridge)
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
