"""Current biases on Loihi 1, exactly: synapses from always-on sources.

A Loihi 1 compartment's bias enters the voltage; a bias on the current (``I[t] += b`` for IR steps
t >= k, see ``snncc/passes/current_bias.py``) has no register. It is lowered as one more synapse
column of the population's feed-forward weights, fed by a source that spikes at every step:

    first layer:   an always-on input axon, held at 1 every step by the driver (snncc adds it);
    deeper layer:  r = refDelay compartments appended to the previous layer, each with a voltage
                   bias above threshold and no inputs, so each fires at steps 0, r, 2r, ...; their
                   synapses carry delays D, D+1, ..., D+r-1, which together deliver one spike at
                   every step from D+1 on.

D = s + k - 1 makes the first delivery land at chip step s + k, the population's IR step k
(s: its timing shift; the timing pass guarantees s + k >= 1). A spike from step m with delay D
arrives at m + 1 + D, so the bias is present at every step from then on and never before.
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.loihi import chip
from snncc.targets.loihi.network import LoihiLayer


def source_bias(pre: LoihiLayer) -> tuple[int, int, int | None]:
    """(mantissa, exponent, own vThMant or None) of a voltage bias that makes a compartment of ``pre``
    fire at every free step: mant * 2**exp > vThMant * 2**6.

    The exponent is the layer's own when it already has biases, else 6 (the one netx assumes).
    The sources share the layer's highest threshold when the 13-bit mantissa reaches above it (no
    extra compartment profile); otherwise they get their own threshold, vThMant 1 (one more profile).
    """
    exp = int(pre.bias_exp) if pre.bias is not None else chip.NETX_BIAS_EXP
    mant = ((int(np.max(pre.v_th_mant)) << chip.V_TH_SHIFT) >> exp) + 1
    if mant <= chip.BIAS_MANT_MAX:
        return mant, exp, None
    return ((chip.V_TH_MANT_MIN << chip.V_TH_SHIFT) >> exp) + 1, exp, chip.V_TH_MANT_MIN


def _extend(value, k: int, fill):
    """A per-neuron register with ``k`` more entries (a scalar register stays a scalar)."""
    if np.ndim(value) == 0:
        return value
    return np.concatenate([np.asarray(value), np.full(k, fill, np.asarray(value).dtype)])


def _pad_rows(a, k: int):
    if a is None or np.ndim(a) == 0:
        return a
    return np.concatenate([a, np.zeros((k,) + a.shape[1:], a.dtype)], axis=0)


def _pad_square(a, k: int):
    if a is None or np.ndim(a) == 0:
        return a
    a = _pad_rows(a, k)
    return np.concatenate([a, np.zeros((a.shape[0], k), a.dtype)], axis=1)


def _append_compartments(pre: LoihiLayer, k: int) -> None:
    """``k`` always-on compartments at the end of ``pre``: no synapses in, a voltage bias above threshold."""
    mant, exp, own_threshold = source_bias(pre)
    bias = np.zeros(pre.n, np.int64) if pre.bias is None else np.asarray(pre.bias, np.int64)
    pre.bias = np.concatenate([bias, np.full(k, mant, np.int64)])
    pre.bias_exp = exp
    pre.weight = _pad_rows(pre.weight, k)
    pre.delay = _pad_rows(pre.delay, k)
    pre.wgt_exp = _pad_rows(pre.wgt_exp, k)
    pre.weight_rec = _pad_square(pre.weight_rec, k)
    pre.delay_rec = _pad_square(pre.delay_rec, k)
    pre.wgt_exp_rec = _pad_square(pre.wgt_exp_rec, k)
    # per-neuron registers: the sources reuse existing profiles (neuron 0's decays, the layer's top threshold)
    if own_threshold is not None:
        pre.v_th_mant = np.broadcast_to(np.asarray(pre.v_th_mant, np.int64), (pre.n,)).copy()
    pre.v_th_mant = _extend(pre.v_th_mant, k, np.max(pre.v_th_mant) if own_threshold is None else own_threshold)
    pre.i_decay = _extend(pre.i_decay, k, np.asarray(pre.i_decay).flat[0])
    pre.v_decay = _extend(pre.v_decay, k, np.asarray(pre.v_decay).flat[0])
    pre.n += k
    pre.always_on += k


def attach(pre: LoihiLayer, post: LoihiLayer, shift: int, terms: list[tuple[int, np.ndarray]],
           exponents: list | None = None) -> None:
    """Add bias-source columns for ``terms`` [(first IR step k, weight column (n,))] to ``post``.

    ``pre`` is the layer before ``post`` (the input layer for the first population); both are
    changed in place. ``shift`` is ``post``'s timing shift. ``exponents``: each column's weight
    exponent (an int or an (n,) array per term); by default the projection's own.
    """
    if not terms:
        return
    repeats = 1 if pre.kind == "input" else int(pre.ref_delay)
    columns, delays, exps = [], [], []
    for j, (start, column) in enumerate(terms):
        first = shift + start - 1
        if first < 0:
            raise SnnccError("a current bias from IR step 0 needs the population shifted by one step (timing pass)",
                             field=f"layer '{post.name}'")
        if first + repeats - 1 > chip.MAX_EXTRA_DELAY:
            raise SnnccError(f"a current bias starting at IR step {start} needs a synaptic delay of "
                             f"{first + repeats - 1} steps; Loihi allows at most {chip.MAX_EXTRA_DELAY}",
                             field=f"layer '{post.name}'")
        if exponents is None and np.ndim(post.wgt_exp):
            raise SnnccError("a projection with per-synapse exponents needs the bias columns' exponents",
                             field=f"layer '{post.name}'")
        exp = post.wgt_exp if exponents is None else exponents[j]
        for p in range(repeats):
            columns.append(np.asarray(column).reshape(-1, 1))
            exps.append(np.broadcast_to(np.asarray(exp, np.int64), (post.n,)).reshape(-1, 1))
            delays.append(first + p)
    k = len(columns)
    if pre.kind == "input":
        pre.n += k
        pre.always_on += k
    else:
        _append_compartments(pre, k)
    n_old = post.weight.shape[1]
    base_exp = np.broadcast_to(np.asarray(post.wgt_exp, np.int64), (post.n, n_old))
    new_exp = np.concatenate([base_exp] + exps, axis=1)
    post.wgt_exp = int(new_exp[0, 0]) if np.all(new_exp == new_exp[0, 0]) else new_exp
    base_delay = np.broadcast_to(np.asarray(post.delay, np.int64), (post.n, n_old))
    post.weight = np.concatenate([post.weight, np.concatenate(columns, axis=1).astype(post.weight.dtype)], axis=1)
    new_delay = np.concatenate([base_delay, np.broadcast_to(np.asarray(delays, np.int64), (post.n, k))], axis=1)
    post.delay = int(new_delay[0, 0]) if np.all(new_delay == new_delay[0, 0]) else new_delay
