"""The v2 core's rules (``literal.py``) in numpy, vectorised over samples and neurons, for small runs: exact, and
without the compiled kernel (``kernel.py``), whose numba import costs more than a few samples take to run.

It runs a *plain* spec (``plain(spec)``: no aliases, every hidden and output threshold > 0; the kernel runs the
others) one step at a time, as ``literal.reference_run`` does, on int64 states:

* a step's deliveries (this step's input events, then last step's hidden events, each in index order, saturating
  after every addition) are summed at once where no partial sum can leave int16: every partial sum lies between
  the state plus all negative contributions and the state plus all positive ones (events are counts >= 0), so
  when both bounds are in range the sum is exact; otherwise the additions are replayed one source at a time
  (c events of one weight, of one sign, equal one saturating addition of c x the weight: ``literal.py``);
* decays, leaks, the summed currents, the bias and the events by the literal rules (``>>`` is numpy's arithmetic
  shift on int64); with every threshold > 0 a neuron's events are min(cap, V // threshold) at once and V - n x
  threshold stays in int16.

``emulator.emulate`` takes this path for a run of few neuron-steps (samples x steps x hidden neurons, ``SMALL_RUN``:
one 256-step sample of 576 hidden neurons, say) while the kernel is not loaded; the tests hold it to XyloSim like
the kernel (tests/xylo/emulation/test_emulator_oracle.py).
"""

from __future__ import annotations

import numpy as np

from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.emulation.result import STATE_NAMES, XyloResult
from snncc.targets.xylo.emulation.weights import effective_weights, wrap16
from snncc.targets.xylo.spec import XyloSpec

SMALL_RUN = 200_000          # samples x steps x hidden neurons up to which this path runs rather than the kernel
LO, HI = CORE.state_min, CORE.state_max


def plain(spec: XyloSpec) -> bool:
    """No aliases and every threshold > 0: the XyloSpec this path runs."""
    return (not any(spec.aliases) and int(np.min(spec.threshold)) > 0 and int(np.min(spec.threshold_out)) > 0)


def _decay(x: np.ndarray, dash: np.ndarray) -> np.ndarray:
    d = np.right_shift(x, dash)
    return np.where(d == 0, np.sign(x), d)


def _deliver(state: np.ndarray, counts: np.ndarray, w: np.ndarray, w_negative: np.ndarray) -> np.ndarray:
    """``state`` (B, ...) after ``counts`` (B, P) events through ``w`` (P, ...) in source order, each addition
    saturated: at once where no partial sum leaves int16, else source by source."""
    if not counts.any():
        return state
    flat = w.reshape(w.shape[0], -1)
    added = (counts @ flat).reshape(state.shape)
    negative = (counts @ w_negative.reshape(w.shape[0], -1)).reshape(state.shape)
    low = state + negative
    if low.min() >= LO and (low + added - 2 * negative).max() <= HI:
        return state + added
    for j in np.flatnonzero(counts.any(axis=0)):
        c = counts[:, j].reshape((-1,) + (1,) * (state.ndim - 1))
        state = np.clip(state + c * w[j], LO, HI)
    return state


def _evolve(isyn: np.ndarray, v: np.ndarray, dash_syn: np.ndarray, dash_mem: np.ndarray, bias: np.ndarray,
            threshold: np.ndarray, cap: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Decay the currents, integrate them and the bias into V, fire (thresholds > 0): (isyn, V, events)."""
    isyn = isyn - _decay(isyn, dash_syn)
    dv = wrap16(-_decay(v, dash_mem))
    dv = np.clip(dv + isyn.sum(axis=-1), LO, HI)
    dv = np.clip(dv + bias, LO, HI)
    v = np.clip(v + dv, LO, HI)
    events = np.where(v >= threshold, np.minimum(v // threshold, cap), 0)
    return isyn, v - events * threshold, events


def run(spec: XyloSpec, x: np.ndarray, *, record: bool = False) -> XyloResult:
    """``x`` (B, T, Nin) event counts (already clipped to 15) through the plain ``spec`` (``plain``)."""
    if not plain(spec):
        raise ValueError("the vectorised path runs specs without aliases whose thresholds are all > 0")
    x = np.asarray(x, np.int64)
    b, t_steps, _ = x.shape
    n, n_out, n_ien, n_oen = spec.n_hidden, spec.n_out, spec.n_ien, spec.n_oen
    w_in, w_rec, w_out = effective_weights(spec)
    w_in_neg, w_rec_neg, w_out_neg = (np.minimum(w, 0) for w in (w_in, w_rec, w_out))
    dash_syn = np.stack([spec.dash_syn, spec.dash_syn_2], axis=1).astype(np.int64)
    dash_mem, dash_mem_out = spec.dash_mem.astype(np.int64), spec.dash_mem_out.astype(np.int64)
    dash_syn_out = spec.dash_syn_out.astype(np.int64)[:, None]
    threshold, threshold_out = spec.threshold.astype(np.int64), spec.threshold_out.astype(np.int64)
    bias, bias_out = spec.bias.astype(np.int64), spec.bias_out.astype(np.int64)
    isyn = np.zeros((b, n, CORE.hidden_synapse_states), np.int64)
    v = np.zeros((b, n), np.int64)
    isyn_o = np.zeros((b, n_out, CORE.output_synapse_states), np.int64)
    v_o = np.zeros((b, n_out), np.int64)
    events = np.zeros((b, n), np.int64)
    out = np.zeros((b, t_steps, n_out), np.uint8)
    rec = {name: np.zeros((b, t_steps, n_out if name.endswith("_out") else n),
                          np.uint8 if name == "spikes" else np.int16) for name in STATE_NAMES} if record else None
    for t in range(t_steps):
        isyn[:, :n_ien] = _deliver(isyn[:, :n_ien], x[:, t], w_in, w_in_neg)          # 1. this step's inputs
        isyn = _deliver(isyn, events, w_rec, w_rec_neg)                                 # 2. last step's events
        isyn_o[:, :, 0] = _deliver(isyn_o[:, :, 0], events[:, n - n_oen:], w_out, w_out_neg)
        isyn, v, events = _evolve(isyn, v, dash_syn, dash_mem, bias, threshold, CORE.max_hidden_spikes)
        isyn_o, v_o, fired = _evolve(isyn_o, v_o, dash_syn_out, dash_mem_out, bias_out, threshold_out,
                                     CORE.max_output_spikes)
        out[:, t] = fired
        if record:
            rec["vmem"][:, t], rec["isyn"][:, t], rec["isyn2"][:, t] = v, isyn[:, :, 0], isyn[:, :, 1]
            rec["spikes"][:, t] = events
            rec["vmem_out"][:, t], rec["isyn_out"][:, t] = v_o, isyn_o[:, :, 0]
    return XyloResult(out, **(rec or {}))
