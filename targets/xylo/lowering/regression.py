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

The normal equations of all neurons of a population are summed block by block over the rows
(``ROW_BLOCK`` rows, the same blocks whatever the sample length), each block of features computed from the
trains when it is needed (``compiled.py``, compiled) and used by every neuron while it is in cache: memory is
bounded by a block of features and the neurons' quadratic forms, never the whole feature matrix.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from snncc.targets.xylo.lowering.chip_form import HiddenFloat, OutputFloat
from snncc.targets.xylo.lowering.decays import grid

ROW_FLOOR = 1e-2          # rows whose regression weight is below this are left out (they hardly count)
ROW_BLOCK = 2048          # rows per block of the normal equations (a block of features stays in cache)
CHUNK_ROWS = 8 * ROW_BLOCK    # rows of features computed at once (whole samples)


def chip_filter(z: np.ndarray, a: float) -> np.ndarray:
    """F[t] = a (F[t-1] + z[t]) along axis 1 of (B, T, n), float64 (``compiled.synaptic``)."""
    from snncc.targets.xylo.lowering.compiled import synaptic

    z = np.asarray(z)
    return synaptic(z, a).reshape(z.shape)


def membrane_filter(z: np.ndarray, b: float) -> np.ndarray:
    """G[t] = b G[t-1] + z[t] along axis 1 of (B, T, n), float64 (``compiled.membrane``)."""
    from snncc.targets.xylo.lowering.compiled import membrane

    z = np.asarray(z)
    return membrane(z, b).reshape(z.shape)


def delayed(z: np.ndarray, d: int) -> np.ndarray:
    """z[:, t - d] (zeros before)."""
    if d == 0:
        return z
    out = np.zeros_like(z)
    if d < z.shape[1]:
        out[:, d:] = z[:, :-d]
    return out


def row_weights(v: np.ndarray, theta: np.ndarray, scale: float) -> np.ndarray:
    """The regression weight of each row: exp(-|V - theta| / (scale theta)), (rows, n)."""
    return np.exp(-np.abs(v - theta[None, :]) / (scale * theta[None, :]))


@dataclass
class Design:
    """Regression data of one population: features (rows, F) and, per neuron, its targets and row weights."""

    features: np.ndarray      # (rows, F)
    target: np.ndarray        # (rows, n) pre-reset voltages
    weight: np.ndarray        # (rows, n)


def design(sources: list[np.ndarray], decays: tuple[float, float], v_pre: np.ndarray, theta: np.ndarray,
           scale: float, constant: bool) -> Design:
    """The whole design at once (small problems and tests; the lowering streams it, ``hidden_blocks``): for each
    synapse k, each source's filtered trains (already delayed), then a constant column."""
    (feats, target, weight), = _hidden_chunks(sources, decays, v_pre, theta, scale, constant, v_pre.shape[0])
    return Design(feats, target, weight)


def _hidden_chunks(sources: list[np.ndarray], decays: tuple[float, ...], v_pre: np.ndarray, theta: np.ndarray,
                   scale: float, constant: bool, samples: int) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(features, targets, weights) of ``samples`` samples at a time: per synapse decay each source's trains
    filtered (``compiled.synaptic``) into the feature columns, then the constant column."""
    from snncc.targets.xylo.lowering.compiled import synaptic

    b_all, steps, n = v_pre.shape
    widths = [src.shape[2] for src in sources]
    f_count = len(decays) * sum(widths) + int(constant)
    for s0 in range(0, b_all, samples):
        s1 = min(b_all, s0 + samples)
        feats = np.empty(((s1 - s0) * steps, f_count), np.float64)
        col = 0
        for a in decays:
            for src, m in zip(sources, widths):
                synaptic(src[s0:s1], a, feats[:, col:col + m])
                col += m
        if constant:
            feats[:, col] = 1.0
        y = v_pre[s0:s1].reshape(-1, n)
        yield feats, y, row_weights(y, theta, scale)


def _blocks(chunks: Iterator[tuple[np.ndarray, ...]]) -> Iterator[tuple[np.ndarray, ...]]:
    """The rows of ``chunks`` (equal-width arrays of rows) regrouped into blocks of ``ROW_BLOCK`` rows (the last
    one shorter): the same blocks however the rows were computed."""
    carry: tuple[np.ndarray, ...] | None = None
    for chunk in chunks:
        if carry is not None:
            chunk = tuple(np.concatenate([c, k]) for c, k in zip(carry, chunk))
            carry = None
        rows = chunk[0].shape[0]
        full = rows - rows % ROW_BLOCK
        for start in range(0, full, ROW_BLOCK):
            yield tuple(a[start:start + ROW_BLOCK] for a in chunk)
        if full < rows:
            carry = tuple(a[full:] for a in chunk)
    if carry is not None and carry[0].shape[0]:
        yield carry


def accumulate(blocks: Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]], neurons, f_count: int
               ) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per neuron j of ``neurons``: (H, b) = (A^T A, A^T y) of its weighted rows, A = w_j * features on the rows
    with w_j >= ROW_FLOOR, summed over the (features, targets, weights) ``blocks`` in order, each block used by
    every neuron while it is in cache.

    A feature that is zero on every row of a block (a source silent in the block's samples: a third of the
    columns of the relayed Braille RSNN's blocks) adds exactly nothing to H or b there, so each block's products
    run over its other columns only (``a_block^T a_block`` added into those rows and columns of H): the same
    sums without the zero terms, which BLAS may group differently in the last bit."""
    from snncc.targets.xylo.lowering.compiled import gather_scaled

    neurons = [int(j) for j in neurons]
    h = np.zeros((len(neurons), f_count, f_count))
    b = np.zeros((len(neurons), f_count))
    buffer = np.empty(ROW_BLOCK * f_count)
    for block, target, weight in blocks:
        block = np.ascontiguousarray(block, np.float64)
        cols = np.flatnonzero(block.any(axis=0))
        if not cols.size:
            continue
        whole = cols.size == f_count
        if not whole:
            block = np.ascontiguousarray(block[:, cols])
            square = (cols[:, None] * f_count + cols[None, :]).ravel()     # those rows and columns of H, flat
        if block.shape[0] * cols.size > buffer.size:       # a block longer than ROW_BLOCK (a caller's own blocks)
            buffer = np.empty(block.shape[0] * cols.size)
        rows_out = buffer[:block.shape[0] * cols.size].reshape(block.shape[0], cols.size)
        for at, j in enumerate(neurons):
            w = weight[:, j]
            keep = np.flatnonzero(w >= ROW_FLOOR)
            if not keep.size:
                continue
            wk = w[keep]
            a = gather_scaled(block, keep, wk, rows_out)      # block[keep] * wk, into the reused buffer
            if whole:
                h[at] += a.T @ a
                b[at] += a.T @ (target[keep, j] * wk)
            else:
                h[at].reshape(-1)[square] += (a.T @ a).ravel()
                b[at][cols] += a.T @ (target[keep, j] * wk)
    return list(zip(h, b))


def normal_equations(d: Design, neurons) -> list[tuple[np.ndarray, np.ndarray]]:
    """``accumulate`` over a whole ``Design`` in blocks of ``ROW_BLOCK`` rows."""
    return accumulate(_blocks(iter([(d.features, d.target, d.weight)])), neurons, d.features.shape[1])


_MEMO: dict | None = None


@contextlib.contextmanager
def remembered() -> Iterator[None]:
    """Within the block, ``hidden_normal_equations`` of the same trains, voltages and settings are computed once
    (the candidates ``single`` and ``single-identified`` of one dash pair fit the same regression). The entries
    hold their inputs, so no array is freed (and its id reused) while they live; they go when the block ends."""
    global _MEMO
    outer, _MEMO = _MEMO, {}
    try:
        yield
    finally:
        _MEMO = outer


def hidden_normal_equations(sources: list[np.ndarray], decays: tuple[float, ...], v_pre: np.ndarray,
                            theta: np.ndarray, scale: float, constant: bool, neurons=None
                            ) -> list[tuple[np.ndarray, np.ndarray]]:
    """``normal_equations`` of ``design(...)`` without the whole design: its features computed a chunk of samples
    at a time (``CHUNK_ROWS`` rows), summed in the same blocks (read-only results: shared within ``remembered``)."""
    key = None
    if _MEMO is not None:
        key = (tuple(id(src) for src in sources), tuple(decays), id(v_pre), theta.tobytes(), float(scale),
               bool(constant), None if neurons is None else tuple(int(j) for j in neurons))
        found = _MEMO.get(key)
        if found is not None:
            return found[1]
    steps = v_pre.shape[1]
    f_count = len(decays) * sum(src.shape[2] for src in sources) + int(constant)
    chunks = _hidden_chunks(sources, decays, v_pre, theta, scale, constant, max(1, CHUNK_ROWS // steps))
    found = accumulate(_blocks(chunks), range(v_pre.shape[2]) if neurons is None else neurons, f_count)
    if key is not None:
        _MEMO[key] = ((list(sources), v_pre), found)
    return found


def ridge_towards(h: np.ndarray, b: np.ndarray, prior: np.ndarray, ridge: float, *, in_place: bool = False
                  ) -> tuple[np.ndarray, np.ndarray]:
    """argmin |A c - y|^2 + lam |c - prior|^2, lam = ridge * mean(diag H); returns (c, H + lam I) (``in_place``: H
    itself becomes H + lam I, no copy)."""
    lam = ridge * max(float(np.trace(h)) / max(len(b), 1), 1e-12)
    rhs = b - h @ prior
    if in_place:
        hr = h
        hr[np.diag_indices_from(hr)] += lam
    else:
        hr = h + lam * np.eye(len(b))
    return prior + np.linalg.solve(hr, rhs), hr


# -- a population's fit ---------------------------------------------------------------------------

def fitted_hidden(pop: HiddenFloat, trains: dict[str, np.ndarray], v_pre: np.ndarray, scale: float,
                  ridge: float) -> HiddenFloat:
    """Refit a ``single`` population's weights to the float graph's voltages (the module doc);
    ``trains``: source -> spike trains already delayed as the IR delivers them (own: delayed 1)."""
    rates = tuple(float(v) for v in grid(pop.dash_syn[0]))
    names = [s for s, k in pop.columns if k == 0]
    constant = bool(np.any(pop.bias != 0))
    sizes = [trains[s].shape[2] for s in names]
    new = {s: np.zeros_like(m) for s, m in pop.weights.items()}
    bias = pop.bias.copy()
    hessians = []
    equations = hidden_normal_equations([trains[s] for s in names], rates, v_pre, pop.theta, scale, constant)
    for j, (h, rhs) in enumerate(equations):
        prior = np.concatenate([pop.weights[s][k, j] for k in range(2) for s in names]
                               + ([pop.bias[j:j + 1]] if constant else []))
        c, hr = ridge_towards(h, rhs, prior, ridge, in_place=_MEMO is None)   # remembered forms stay as they are
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
    hs = []
    for h, _ in hidden_normal_equations([trains[s] for s in names], rates, v_pre, pop.theta, scale, constant):
        hs.append(h + ridge * max(float(np.trace(h)) / len(h), 1e-12) * np.eye(len(h)))
    pop.hessians = hs
    return pop


def _output_chunks(out: OutputFloat, pre: np.ndarray, own: np.ndarray, v_pre: np.ndarray, scale: float,
                   rates: tuple[float, float], samples: int) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(features, targets, weights) of the output neurons' regression for the dash pair of ``rates``, a chunk of
    samples at a time (``fitted_output``)."""
    from snncc.targets.xylo.lowering.compiled import membrane, synaptic

    a, b = rates
    b_all, steps, n = v_pre.shape
    for s0 in range(0, b_all, samples):
        s1 = min(b_all, s0 + samples)
        shape = (s1 - s0, steps)
        current = synaptic(pre[s0:s1], a).reshape(shape + (pre.shape[2],))
        feat = membrane(current, b)
        reset = membrane(delayed(np.asarray(own[s0:s1], np.float64), 1), b) * b   # sum_{m<t} b^(t-m) s[m]
        register = membrane(np.ones(shape + (1,)), b) * out.bias[None, :]       # the fixed b_V part
        v = v_pre[s0:s1].reshape(-1, n)
        target = v + out.theta[None, :] * reset - register
        yield feat, target, np.exp(-np.abs(v - out.theta) / (scale * out.theta))


def fitted_output(out: OutputFloat, pre: np.ndarray, own: np.ndarray, v_pre: np.ndarray, scale: float,
                  ridge: float) -> OutputFloat:
    """Refit output weights: V_pre + theta sum_{m<t} b^(t-m) s[m] (the chip's own reset, moved to the target;
    the voltage-bias register's part taken out) ~ membrane-filtered synaptic traces of the presynaptic spikes
    (``pre`` delayed as the IR delivers them; with ``bias_source``, its last column is the source's train)."""
    new = out.weight.copy()
    hs = []
    samples = max(1, CHUNK_ROWS // v_pre.shape[1])
    for dash_pair in {(int(a), int(b)) for a, b in zip(out.dash_syn, out.dash_mem)}:
        rates = tuple(float(v) for v in grid(np.asarray(dash_pair)))
        sel = np.flatnonzero((out.dash_syn == dash_pair[0]) & (out.dash_mem == dash_pair[1]))
        chunks = _output_chunks(out, pre, own, v_pre, scale, rates, samples)
        for j, (h, rhs) in zip(sel, accumulate(_blocks(chunks), sel, pre.shape[2])):
            c, hr = ridge_towards(h, rhs, out.weight[j], ridge)
            new[j] = c
            hs.append((j, hr))
    hessians = [h for _, h in sorted(hs, key=lambda p: p[0])]
    return OutputFloat(out.name, out.source, out.theta, out.dash_syn, out.dash_mem, new, out.bias, "identified", hessians,
                       out.bias_source)
