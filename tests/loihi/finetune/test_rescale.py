"""Loihi fine-tuning's rescaled starting points (targets/loihi/rescale.py), the shared rounding (snncc/rounding.py)."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.finetune.engine import FinetuneConfig
from snncc.finetune.inputs import split_inputs
from snncc.finetune.teacher import run_teacher
from snncc.frontends.builders import snn_graph
from snncc.rounding import damped, round_with_feedback
from snncc.targets.loihi.bundle.portability import netx_runnable
from snncc.targets.loihi.finetune.export import validate_export
from snncc.targets.loihi.finetune.run import finetune_loihi
from snncc.targets.loihi.lowering.lower import lower_model
from snncc.targets.loihi.finetune.rescale import rescaled
from snncc.targets.loihi.options import LoihiOptions

STEPS = 32


def test_rows_sharing_a_form_round_as_one_by_one():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(300, 9)) + rng.normal(size=(300, 1))
    h = damped(a.T @ a, 0.1)
    c = rng.normal(0, 20, (5, 9))
    together = round_with_feedback(h, c, 2.0, -128, 127)
    assert together.shape == (5, 9)
    for row, k in zip(c, together):
        assert round_with_feedback(h, row, 2.0, -128, 127).tolist() == k.tolist()
    near = np.clip(np.round(c / 2.0), -128, 127)
    err = lambda k, r: float((2 * k - r) @ h @ (2 * k - r))  # noqa: E731
    assert sum(err(k, r) for k, r in zip(together, c)) < sum(err(k, r) for k, r in zip(near, c))


def exact_graph():
    """6 -> 8 (recurrent) -> 3, every neuron's incoming weights even multiples of 1 / s_i with the largest
    at 254 / s_i (s_i an integer per neuron): per-neuron scales hold them exactly, per-layer ones do not."""
    rng = np.random.default_rng(3)

    def block(n_out, n_in_cols, scales):
        k = rng.integers(-60, 61, (n_out, n_in_cols)).astype(np.float64)
        k[np.arange(n_out), rng.integers(0, n_in_cols, n_out)] = 127.0
        return 2.0 * k / scales[:, None]

    s_hidden = np.array([40, 55, 70, 90, 110, 130, 160, 200], np.float64)
    s_out = np.array([60, 100, 150], np.float64)
    both = block(8, 14, s_hidden)
    w_in, w_rec = both[:, :6], both[:, 6:]
    w_out = block(3, 8, s_out)
    g = snn_graph(w_in.T, w_out.T, w_rec.T, dt=1e-3, tau_syn=4e-3, tau_mem=8e-3, threshold=1.0)
    return g, s_hidden, s_out, (w_in, w_rec, w_out)


def test_per_neuron_scales_hold_weights_that_fit_them_exactly():
    g, s_hidden, s_out, (w_in, w_rec, w_out) = exact_graph()
    low = lower_model(g, LoihiOptions(scale="per-layer"), t_sample=STEPS)
    x = split_inputs(width=6, steps=STEPS, train=16, validation=4, held_out=4, density=0.3, seed=0).x[:16]
    spikes = run_teacher(low.trained, x, tuple(c.lif for c in low.layers), voltage=False).spikes
    net = rescaled(low, low.network, x, spikes, per_neuron=True)
    hidden, out = net.layers[1], net.layers[2]
    assert np.asarray(hidden.v_th_mant).tolist() == s_hidden.astype(int).tolist()
    assert np.asarray(out.v_th_mant).tolist() == s_out.astype(int).tolist()
    assert np.array_equal(hidden.weight[:, :6], np.rint(w_in * s_hidden[:, None]))
    assert np.array_equal(hidden.weight_rec, np.rint(w_rec * s_hidden[:, None]))
    assert np.array_equal(out.weight, np.rint(w_out * s_out[:, None]))
    # the format is the rule's (exponents, portability) and the compiler's checks accept the network
    for a, b in zip(net.layers[1:], low.network.layers[1:]):
        assert a.wgt_exp == b.wgt_exp and a.wgt_exp_rec == b.wgt_exp_rec
    assert [str(gap) for gap in netx_runnable(net)] == [str(gap) for gap in netx_runnable(low.network)]
    checks = validate_export(low, net, STEPS)
    assert checks["timing_exact"] and checks["quantized_params_exact"] and checks["kernel_exact"]
    # at the rule's own (layer) scales the threshold stays the layer's one register
    same = rescaled(low, low.network, x, spikes, per_neuron=False)
    assert same.layers[1].v_th_mant == low.network.layers[1].v_th_mant


def test_fine_rule_has_no_rescaled_start():
    g, *_ = exact_graph()
    low = lower_model(g, LoihiOptions(scale="fine"), t_sample=STEPS)
    x = np.zeros((2, STEPS, 6), np.uint8)
    spikes = run_teacher(low.trained, x, tuple(c.lif for c in low.layers), voltage=False).spikes
    assert rescaled(low, low.network, x, spikes) is None     # per-synapse exponents: the format has no row scale


def test_starting_point_search_measures_the_rescaled_networks():
    g, *_ = exact_graph()
    split = split_inputs(width=6, steps=STEPS, train=48, validation=40, held_out=40, density=0.25, seed=0)
    out = finetune_loihi(g, LoihiOptions(scale="per-layer"), split, config=FinetuneConfig(epochs=1, batch=16))
    names = [s["name"] for s in out.record.starting_points]
    assert "compensated rounding at the rule's scales" in names
    assert "per-neuron scales (at most 8 per layer), compensated rounding" in names
    assert out.validation["timing_exact"] and out.validation["quantized_params_exact"]
    assert out.validation["kernel_exact"]


def test_scale_groups_lose_the_fewest_bits():
    from itertools import combinations

    from snncc.targets.loihi.finetune.rescale import scale_groups

    top = np.array([0.5, 3.0, 0.6, 2.9, 1.1, 0.0, 1.0, 6.0])
    assert scale_groups(top, 8).tolist() == top.tolist()          # as many groups as neurons: unchanged
    grouped = scale_groups(top, 3)
    assert np.unique(grouped[top > 0]).size <= 3 and grouped[5] == 0.0
    assert np.all(grouped >= top)                                   # no weight leaves the 8-bit range
    lost = lambda g: float(np.sum(np.log2(g[top > 0] / top[top > 0])))  # noqa: E731
    live = np.sort(top[top > 0])
    best = np.inf
    for cuts in combinations(range(1, live.size), 2):               # every split of the sorted maxima in 3
        bounds = (0,) + cuts + (live.size,)
        g = np.concatenate([np.full(b - a, live[b - 1]) for a, b in zip(bounds, bounds[1:])])
        best = min(best, float(np.sum(np.log2(g / live))))
    assert lost(grouped) == pytest.approx(best)
