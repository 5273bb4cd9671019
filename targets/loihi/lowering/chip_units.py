"""The quantized IR restated in chip units, so that float simulators decide ties as the chip does.

A LIF population's spikes do not change when its current, voltage, incoming weights, biases and
threshold are all multiplied by one factor s > 0 (the equations are linear in them; spikes are
0/1). The quantized graph stores values k * 2**e / s (s: the population's weight scale); times s they
are k * 2**e: integers or dyadic fractions, which float64 adds exactly. Without this, a voltage that
equals the threshold on the chip (frequent for non-leaky IF layers with integer weights; the chip
fires only when v > threshold) lands a rounding error above or below it depending on the order a
simulator sums in.
"""

from __future__ import annotations

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense

GRID = 2.0 ** 24     # quantized values are multiples of 2**-24 or coarser once in chip units


def _snap(values: np.ndarray) -> np.ndarray:
    """Undo the float error of (k * 2**e / s) * s: back onto the dyadic grid the chip values lie on."""
    out = np.asarray(values, np.float64) * GRID        # one array, rounded and divided in place (the same bits)
    np.round(out, out=out)
    out /= GRID
    return out


def in_chip_units(quantized: Graph, record) -> Graph:
    """``quantized`` with each population (``record.layers``) scaled by its scale s: incoming Dense
    weights and biases, the LIF's threshold and bias. A new graph with the same spikes."""
    rescaled = [quantized.node(p).weight for lq in record.layers if isinstance(quantized.node(lq.lif), LIF)
                for p in quantized.predecessors(lq.lif) if isinstance(quantized.node(p), Dense)]
    g = quantized.copy(replaced=rescaled)         # those weights are assigned anew below
    for lq in record.layers:
        s = float(lq.scale)
        op = g.node(lq.lif)
        if not isinstance(op, LIF):
            continue
        op.threshold = np.where(np.isfinite(op.threshold), _snap(op.threshold * s), op.threshold)
        if op.bias is not None:
            op.bias = _snap(op.bias * s)
        for pred in g.predecessors(lq.lif):
            dense = g.node(pred)
            if isinstance(dense, Dense):
                dense.weight = _snap(dense.weight * s)
                if dense.bias is not None:
                    dense.bias = _snap(dense.bias * s)
    return g
