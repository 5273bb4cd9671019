"""Random, active Xylo networks and inputs for the oracle tests (seeded; hypothesis draws the knobs).

A network is drawn from a handful of structural choices (sizes, synapse axis, shifts, weight
density, threshold scale, how many biases and aliases) plus a seed for the numbers. Thresholds
are set relative to the largest effective input weight int16(w << shift_in), so every network
is driven; input rasters are dense enough, with counts up to ``max_count`` (above 15: clipped).
One hidden and one output neuron are pacemakers (the largest bias, only excitatory weights in),
so no network is silent: they fire every step and their events reach the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.xylo.chip import CORE, XyloChip
from snncc.targets.xylo.spec import XyloSpec


@dataclass(frozen=True)
class Knobs:
    seed: int
    n_in: int
    n_hidden: int
    n_out: int
    n_ien: int
    n_oen: int
    synapse_axis: int           # 0: 2-D weights (synapse 1 only); 1 or 2: a 3-D weight array with that many
    shift_in: int
    shift_rec: int
    shift_out: int
    density: float              # fraction of non-zero recurrent weights
    threshold_scale: float      # thresholds ~ this x the largest effective input weight
    bias_fraction: float
    alias_fraction: float
    negative_thresholds: bool   # a few thresholds <= 0 (they wrap V on firing)
    max_fanout: int | None = None


def _effective_scale(shift: int) -> int:
    """The largest |int16(w << shift)| over int8 w (the wrap makes it non-monotonic in shift)."""
    w = np.arange(CORE.weight_min, CORE.weight_max + 1, dtype=np.int64) << shift
    return int(np.abs(((w + 2**15) & 0xFFFF) - 2**15).max())


def _excitatory(w: np.ndarray, shift: int) -> np.ndarray:
    """|w|, and 0 where int16(|w| << shift) wraps negative: weights that can only excite."""
    w = np.minimum(np.abs(w), CORE.weight_max)
    effective = ((w.astype(np.int64) << shift) + 2**15 & 0xFFFF) - 2**15
    return np.where(effective >= 0, w, 0)


def random_spec(k: Knobs) -> XyloSpec:
    rng = np.random.default_rng(k.seed)
    n, syn = k.n_hidden, max(1, k.synapse_axis)

    def weights(shape, density, positive_bias=0.0):
        w = rng.integers(CORE.weight_min, CORE.weight_max + 1, size=shape)
        w = np.where(rng.random(shape) < positive_bias, np.minimum(np.abs(w), CORE.weight_max), w)
        return np.where(rng.random(shape) < density, w, 0)

    w_in = weights((k.n_in, k.n_ien, syn), 0.7, positive_bias=0.6)
    w_rec = weights((n, n, syn), k.density)
    if k.max_fanout is not None:   # keep at most max_fanout targets per neuron
        for j in range(n):
            targets = np.flatnonzero(np.any(w_rec[j] != 0, axis=1))
            if targets.size > k.max_fanout:
                w_rec[j, rng.choice(targets, targets.size - k.max_fanout, replace=False)] = 0
    if k.synapse_axis == 0:
        w_in, w_rec = w_in[:, :, 0], w_rec[:, :, 0]
    w_out = weights((k.n_oen, k.n_out), 0.8, positive_bias=0.5)

    drive = max(1, _effective_scale(k.shift_in))
    def thresholds(size):
        th = np.maximum(1, np.round(drive * k.threshold_scale * rng.uniform(0.3, 3.0, size))).astype(np.int64)
        if k.negative_thresholds:
            th = np.where(rng.random(size) < 0.15, -rng.integers(0, 2000, size), th)
        return np.minimum(th, CORE.threshold_max)

    def biases(size):
        b = rng.integers(-3000, 3000, size) * (rng.random(size) < k.bias_fraction)
        return b.astype(np.int64)

    aliases = [[int(rng.integers(0, n))] if rng.random() < k.alias_fraction else [] for _ in range(n)]
    dashes = lambda size: rng.integers(0, CORE.dash_max + 1, size)   # noqa: E731
    threshold, threshold_out, bias, bias_out = thresholds(n), thresholds(k.n_out), biases(n), biases(k.n_out)
    pace, pace_out = int(rng.integers(0, n)), int(rng.integers(0, k.n_out))
    if pace < k.n_ien:
        w_in[:, pace] = _excitatory(w_in[:, pace], k.shift_in)
    w_rec[:, pace] = _excitatory(w_rec[:, pace], k.shift_rec)
    w_out[:, pace_out] = _excitatory(w_out[:, pace_out], k.shift_out)
    bias[pace], bias_out[pace_out] = CORE.bias_max, CORE.bias_max
    threshold[pace] = max(1, threshold[pace])
    threshold_out[pace_out] = max(1, threshold_out[pace_out])
    return XyloSpec(
        weights_in=w_in, weights_rec=w_rec, weights_out=w_out,
        dash_mem=dashes(n), dash_syn=dashes(n), dash_syn_2=dashes(n),
        dash_mem_out=dashes(k.n_out), dash_syn_out=dashes(k.n_out),
        threshold=threshold, threshold_out=threshold_out,
        bias=bias, bias_out=bias_out,
        weight_shift_in=k.shift_in, weight_shift_rec=k.shift_rec, weight_shift_out=k.shift_out,
        aliases=aliases, dt=1e-3)


def random_inputs(seed: int, batch: int, steps: int, n_in: int, density: float, max_count: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    counts = rng.integers(1, max_count + 1, size=(batch, steps, n_in))
    return (counts * (rng.random((batch, steps, n_in)) < density)).astype(np.uint8)


def chip_sized_knobs(chip: XyloChip, seed: int) -> Knobs:
    """A network at the chip's limits: all inputs, hidden and output neurons, the most expansion
    neurons, its synapses, fan-out at most the chip's."""
    return Knobs(seed=seed, n_in=chip.max_inputs, n_hidden=chip.max_hidden, n_out=chip.max_outputs,
                 n_ien=chip.max_input_expansion, n_oen=chip.max_output_expansion,
                 synapse_axis=chip.synapses_per_hidden if chip.synapses_per_hidden > 1 else 0,
                 shift_in=6, shift_rec=4, shift_out=5, density=1.0, threshold_scale=0.3, bias_fraction=0.3,
                 alias_fraction=0.05, negative_thresholds=False, max_fanout=min(chip.max_fanout, 64))
