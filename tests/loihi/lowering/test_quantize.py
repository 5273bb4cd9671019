"""The paper's quantization rules, and the th1 done-when check of issue 3."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.frontends import LoadOptions, load_model
from snncc.targets.loihi.lowering.quantize import decay_register, quantize_graph, quantize_weights, samples_steps, weight_scale
from snncc.targets.loihi import target
from snncc_test_helpers import TH1_PARAMS
from tests.loihi.helpers import small_graph


def test_weight_scale_rule():
    assert weight_scale(0.43) == 595 and weight_scale(1.0) == 256 and weight_scale(256.0) == 1
    with pytest.raises(SnnccError, match="per-layer"):
        weight_scale(300.0)
    with pytest.raises(SnnccError):
        weight_scale(0.0)


def test_quantize_weights_even_half_to_even_and_clipped():
    w = np.array([1.0, -1.0, 0.5, 3.0 / 256, 5.0 / 256, 1.0 / 256, -3.0 / 256])
    q = quantize_weights(w, 256)
    # 256 -> 254 (clip), -256 stays, 128 even, 3/2 = 1.5 -> 2 -> 4, 5/2 = 2.5 -> 2 (half to even) -> 4, 0.5 -> 0
    assert q.tolist() == [254, -256, 128, 4, 4, 0, -4]
    assert all(v % 2 == 0 for v in q)


def test_decay_registers():
    assert decay_register(0.005, 0.006) == 2315 and decay_register(0.005, 0.06) == 327
    assert decay_register(0.005, 0.06, "euler") == int(4096 * 0.005 / 0.06) == 341
    assert decay_register(1e-4, 1e9) == 0
    with pytest.raises(SnnccError, match="0..4096"):
        decay_register(0.01, 0.005, "euler")


def test_positive_maximum_rounding_to_256_is_clipped_and_reported():
    g = small_graph()
    for name in ("w_in", "w_rec", "w_out"):
        g.node(name).weight[:] = np.clip(g.node(name).weight, -0.99, 0.99)
    w = g.node("w_in").weight
    w[0, 0] = 1.0      # the maximum: w_scale = 256, rounds to +256 -> clipped to 254
    w[1, 1] = -1.0
    _, rec = quantize_graph(g, "global")
    assert rec.w_scale == 256
    assert rec.clipped_total >= 1
    assert next(p for p in rec.projections if p.dense == "w_in").clipped >= 1


def test_th1_weight_list_compiles_to_the_papers_registers(tmp_path):
    gen = torch.Generator().manual_seed(3)
    w_in, w_out, v_rec = torch.randn(48, 450, generator=gen) * 0.1, torch.randn(450, 28, generator=gen) * 0.1, \
        torch.randn(450, 450, generator=gen) * 0.02
    path = tmp_path / "weights_th1.pt"
    torch.save([w_in, w_out, v_rec], path)
    params = tmp_path / "parameters_th1.txt"
    params.write_text(TH1_PARAMS)
    graph = load_model(path, LoadOptions(params=params))
    art = target.lower(graph, {"timing": "exact", "scale": "global"})
    net = art.network
    w_scale = math.floor(256 / max(float(t.abs().max()) for t in (w_in, w_out, v_rec)))
    assert art.quantization["w_scale"] == w_scale
    assert net.t_sample == 270
    hidden, out = net.layers[1], net.layers[2]
    for lay in (hidden, out):
        assert (lay.i_decay, lay.v_decay, lay.v_th_mant, lay.wgt_exp) == (2315, 327, w_scale, 0)
        assert lay.ref_delay == 2
    rule = lambda w: np.clip(np.round(w.double().numpy().T * w_scale / 2) * 2, -256, 254)  # noqa: E731
    assert np.array_equal(hidden.weight, rule(w_in))
    assert np.array_equal(hidden.weight_rec, rule(v_rec))
    assert np.array_equal(out.weight, rule(w_out))
    assert (hidden.delay, hidden.delay_rec, out.delay) == (1, 2, 1)   # SpyTorch order lowered exactly
    v = art.validation
    assert v["timing_exact"] and v["quantized_params_exact"] and v["kernel_exact"]
    paper = target.lower(graph, {"timing": "paper", "scale": "global"}).network
    assert (paper.layers[1].delay, paper.layers[1].delay_rec, paper.layers[2].delay) == (0, 0, 0)
    assert paper.layers[1].ref_delay == 1


def test_t_sample_from_recording_length_or_input():
    g = small_graph(steps=40)
    assert samples_steps(g)[0] == 40
    g.metadata.pop("recording_length_s")
    assert samples_steps(g, 33)[0] == 33


def test_per_layer_scale_uses_exponents_and_stays_exact():
    g = small_graph(seed=2)
    g.node("w_out").weight *= 0.05          # a weak readout projection
    art = target.lower(g, {"scale": "per-layer"})
    q = art.quantization
    assert q["rule"] == "per-layer"
    assert art.validation["quantized_params_exact"] and art.validation["kernel_exact"]
    # every projection fills at least half its 8-bit range
    assert all(p["range_used"] > 0.5 for p in q["projections"])


def test_split_exponents_keep_small_weights_and_outliers():
    """Outliers keep the exponent that fits them; the bulk gets a finer one (two synapse formats)."""
    from snncc.targets.loihi.lowering.quantize import bulk_max, synapse_exponents

    w = np.full((4, 5), 0.01)
    w[0, 0] = 1.0                                     # 100x the rest
    assert bulk_max(w) == pytest.approx(0.01)
    e = synapse_exponents(w, 256, -6, 0)
    assert e[0, 0] == 0 and np.all(e.flat[1:] == -6)
    g = small_graph(seed=2)
    rec = g.node("w_rec").weight
    rec.flat[[3, 50, 97]] = 100 * np.median(np.abs(rec))
    plain, rp = quantize_graph(g, "per-layer")
    split, rs = quantize_graph(g, "per-layer", split={"w_rec"})
    ps = {p.dense: p for p in rs.projections}["w_rec"]
    pp = {p.dense: p for p in rp.projections}["w_rec"]
    assert ps.wgt_exp_outliers == pp.wgt_exp and ps.wgt_exp < pp.wgt_exp and ps.outliers == 3
    assert ps.rms_error < pp.rms_error / 4 and ps.zeroed < pp.zeroed
    exps = ps.exponents(rec)
    np.testing.assert_allclose(split.node("w_rec").weight, quantize_weights(rec, ps.scale, exps) * 2.0 ** exps / ps.scale)
    # the outliers themselves are quantized as before
    np.testing.assert_allclose(split.node("w_rec").weight.flat[[3, 50, 97]], plain.node("w_rec").weight.flat[[3, 50, 97]])


def test_split_lowers_exactly_and_auto_keeps_to_portable_rules():
    g = small_graph(seed=3, order="loihi")
    rec = g.node("w_rec").weight
    rec.flat[[5, 77, 130]] = 100 * np.median(np.abs(rec))
    art = target.lower(g, {"scale": "split"})
    assert art.validation["timing_exact"] and art.validation["quantized_params_exact"] and art.validation["kernel_exact"]
    exp = art.network.layers[1].wgt_exp_rec
    assert np.ndim(exp) == 2 and np.count_nonzero(exp == exp.max()) == 3
    auto = target.lower(g, {"scale": "auto"})
    errors = auto.quantization["calibration"]["errors"]
    assert set(errors) == {"global", "per-layer"} and auto.quantization["rule"] in errors, errors   # netx runs both


def test_per_neuron_thresholds_and_decays_become_per_neuron_registers():
    g = small_graph(seed=4)
    rng = np.random.default_rng(0)
    hidden = g.node("hidden")
    hidden.threshold = rng.uniform(0.8, 1.2, hidden.n)
    hidden.tau_mem = rng.choice([0.04, 0.06, 0.08], hidden.n)
    q, rec = quantize_graph(g, "global")
    lq = {layer.lif: layer for layer in rec.layers}
    s = rec.w_scale
    assert lq["hidden"].v_th_mant == [round(t * s) for t in hidden.threshold]
    assert lq["hidden"].v_decay == [decay_register(g.dt, t) for t in hidden.tau_mem]
    assert isinstance(lq["hidden"].i_decay, int) and isinstance(lq["out"].v_th_mant, int)   # shared: one profile
    np.testing.assert_allclose(q.node("hidden").threshold, np.array(lq["hidden"].v_th_mant) / s)
    art = target.lower(g, {"scale": "global"})
    assert art.validation["quantized_params_exact"]
    np.testing.assert_array_equal(art.network.layers[1].v_th_mant, lq["hidden"].v_th_mant)
