"""The 'fine' scale rule: every synapse its finest weight exponent, decays rounded to nearest; lowered
bit-exactly (the lowering's own checks: float twin, quantized twin, kernel vs readable statement)."""

from __future__ import annotations

import numpy as np

from snncc.targets.loihi.chip import WEIGHT_MAX
from snncc.targets.loihi.lowering.quantize import decay_register, finest_exponents, quantize_graph, quantize_weights
from snncc.targets.loihi import target
from tests.loihi.helpers import small_graph


def test_finest_exponents_keep_eight_bits_of_every_weight():
    w = np.array([0.0, 1e-4, 0.01, 0.3, 2.0, -5.0, 50.0])
    s = 256.0
    e = finest_exponents(w, s)
    q = quantize_weights(w, s, e)
    assert np.all(np.abs(q) <= 256) and np.all(e >= -6) and np.all(e <= 7)
    big = np.abs(w) * s / 2.0 ** e >= 128       # mantissa in the top half: relative error <= 1/128
    back = q * 2.0 ** e / s
    assert np.all(np.abs(back - w)[big] <= np.abs(w)[big] / 128 + 1e-12)
    assert np.all(np.abs(q[e > -6]) >= 126)     # a finer exponent would not have fitted
    assert e[0] == -6 and q[0] == 0


def test_nearest_decay_rounding():
    assert decay_register(1e-4, 1e-3, "euler") == 409                       # the paper truncates 409.6
    assert decay_register(1e-4, 1e-3, "euler", rounding="nearest") == 410


def test_fine_rule_lowers_bit_exactly_with_per_synapse_exponents():
    g = small_graph(seed=3)
    rec = g.node("w_rec").weight
    rec.flat[[5, 77, 130]] = 100 * np.median(np.abs(rec))
    q, record = quantize_graph(g, "fine")
    assert record.rule == "fine"
    for p in record.projections:
        assert p.per_synapse and len(p.exponents_used) >= 2 and p.clipped == 0
        assert p.range_used <= 1.0
    split = quantize_graph(g, "per-layer", split={"w_rec"})[1]
    rms = {p.dense: p.rms_error for p in split.projections}
    assert all(p.rms_error < rms[p.dense] for p in record.projections), (record.projections, rms)
    art = target.lower(g, {"scale": "fine"})
    v = art.validation
    assert v["timing_exact"] and v["quantized_params_exact"] and v["kernel_exact"]
    assert np.ndim(art.network.layers[1].wgt_exp_rec) == 2 and not any(v["overflow"].values())
    assert np.all(np.abs(art.network.layers[1].weight_rec) <= WEIGHT_MAX + 2)
