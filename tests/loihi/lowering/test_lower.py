"""Lowering IR graphs for Loihi: exact timing, honest refusals, scale choice, the float-equivalence check."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.frontends.builders import lstm_graph
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.ir.simulate import simulate
from snncc.targets.loihi import lower_model, target
from snncc.targets.loihi.emulation.emulator import reference_run
from snncc.targets.loihi.lowering.registers import float_twin
from snncc.targets.loihi.checks.exactness import loihi_spikes
from snncc.targets.loihi.options import LoihiOptions
from tests.loihi.helpers import small_graph


def _x(seed, batch=6, steps=40, width=8, p=0.2):
    return (np.random.default_rng(seed).random((batch, steps, width)) < p).astype(np.uint8)


@pytest.mark.parametrize("order", ["spytorch", "loihi"])
def test_without_quantization_the_lowered_model_reproduces_the_float_model_spike_for_spike(order):
    graph = small_graph(order=order, seed=4)
    low = lower_model(graph, LoihiOptions(timing="exact"))
    x = _x(1)
    ref = simulate(graph, x, record="spikes")
    twin_net = float_twin(low.network, graph, low.layers)
    twin = reference_run(twin_net, x, arithmetic="float", record="all")
    got = loihi_spikes(twin, twin_net, low.layers, low.timing_record.shifts, x.shape[1])
    for name in ("hidden", "out"):
        expected = np.asarray(ref.spikes[name]).astype(np.uint8)
        assert expected.sum() > 0
        assert np.array_equal(got[name], expected), name


def test_paper_timing_changes_the_order_and_check_measures_it():
    graph = small_graph(order="spytorch", seed=5)
    x, labels = _x(2, batch=24), np.random.default_rng(0).integers(0, 5, 24)
    rec = target.check(graph, x, labels, {"timing": "paper", "scale": "global"})
    assert rec.details["timing"] == "paper" and "ir_loihi_order" in [s.key for s in rec.stages]
    spikes = rec.details["spike_agreement"]
    assert spikes["loihi_order_vs_trained"]["hidden"] < 1.0   # the authors' export changes the order
    exact = target.check(graph, x, labels, {"timing": "exact", "scale": "global"})
    assert exact.causes["timing"] == 0.0 and "ir_loihi_order" not in [s.key for s in exact.stages]
    assert exact.details["spike_agreement"]["loihi_order_vs_trained"] == {"hidden": 1.0, "out": 1.0}
    total = sum(v for v in exact.causes.values() if v is not None)
    assert abs(total - exact.total_points) < 1e-9


def test_zero_delay_feed_forward_is_shifted_exactly():
    graph = small_graph(order="loihi", seed=6, recurrent=False)
    graph.set_delay("input", "w_in", 0)
    graph.set_delay("hidden", "w_out", 0)
    art = target.lower(graph, {"scale": "global"})
    assert art.timing["shifts"] == {"hidden": 1, "out": 2} and art.timing["output_shift"] == 2
    assert art.network.t_sample == 40 + 2
    assert art.validation["timing_exact"] and any("delay 0" in c for c in art.timing["changes"])


def test_lstm_is_refused_for_loihi():
    rng = np.random.default_rng(0)
    g = lstm_graph(rng.normal(size=(16, 3)), rng.normal(size=(16, 4)), None, rng.normal(size=(2, 4)), None,
                   dt=0.01, signal="analog")
    with pytest.raises(SnnccError, match="LSTM cannot run on Loihi"):
        target.lower(g, {})


def test_subtract_reset_is_refused_unless_allowed():
    g = small_graph(seed=7)
    g.node("hidden").reset = "subtract"
    with pytest.raises(SnnccError, match="reset"):
        target.lower(g, {})
    art = target.lower(g, {"allow_reset_change": True})
    assert any("subtract -> zero" in c for c in art.timing["changes"])


def _bias_graph(placement):
    g = Graph(0.001, metadata={"recording_length_s": 0.04})
    rng = np.random.default_rng(3)
    g.add("input", Input(4))
    g.add("w", Dense(rng.normal(0, 1, (6, 4)), bias=None))
    g.add("lif", LIF(6, 0.005, 0.02, 1.0, bias=rng.normal(0, 0.05, 6), bias_placement=placement))
    g.add("ro", Readout(6))
    g.add("out", Output(6))
    g.connect("input", "w", 1)
    g.connect("w", "lif")
    g.connect("lif", "ro")
    g.connect("ro", "out")
    return g


def test_voltage_bias_is_a_register_and_current_bias_an_always_on_axon():
    art = target.lower(_bias_graph("voltage"), {"scale": "global"})
    assert art.network.layers[1].bias is not None and art.validation["quantized_params_exact"]
    assert art.network.layers[0].always_on == 0
    art = target.lower(_bias_graph("current"), {"scale": "global"})
    assert art.network.layers[1].bias is None and art.network.layers[0].always_on == 1
    assert art.validation["timing_exact"] and art.validation["quantized_params_exact"]


def test_auto_scale_handles_an_outlier_recurrent_matrix():
    graph = small_graph(seed=8, n_h=30, order="loihi")     # the chip's own order: nothing netx lacks
    v = graph.node("w_rec").weight
    v[0, 1] = 100 * float(np.median(np.abs(v)))        # one outlier: 100x the median
    art = target.lower(graph, {"scale": "auto"})
    q = art.quantization
    assert q["calibration"] is not None and "global" in q["calibration"]["errors"]
    errors = q["calibration"]["errors"]
    # portable by default: auto measures only the rules netx runs as written; the paper's global rule is kept
    # unless the other measures better beyond the 95 % interval on the second look's samples (stated)
    assert set(errors) == {"global", "per-layer"}, errors
    assert q["rule"] in ("global", "per-layer") and art.portability["netx_runnable"], (q["reason"], art.portability)
    assert "netx-runnable" in q["reason"] and "median" in q["reason"], q["reason"]
    second = q["calibration"]["significance"]
    if errors["per-layer"] < errors["global"]:      # the second look ran and decided
        assert second["samples"] == 256 and set(second["agreement"]) == {"global", "per-layer"}
        a, b = second["agreement"]["per-layer"], second["agreement"]["global"]
        assert (q["rule"] == "per-layer") == (a["low"] > b["high"]) and f"on {second['samples']} samples" in q["reason"]
    else:
        assert q["rule"] == "global" and second is None
    # the rules netx cannot express are used when asked for: split exponents on the outlier projection
    split = target.lower(graph, {"scale": "split"})
    assert np.ndim(split.network.layers[1].wgt_exp_rec) == 2 and not split.portability["netx_runnable"]
    assert "per-synapse weight exponents" in split.portability["line"]
    plain = target.lower(small_graph(seed=8, order="loihi"), {"scale": "auto"})
    assert plain.quantization["rule"] == "global" and "no outlier" in plain.quantization["reason"]


def test_auto_measures_every_rule_when_the_model_needs_what_netx_lacks():
    """The authors' order (refractory 2, input delay 2 on the recurrent layer): no rule is portable, so auto measures
    every rule, keeps the paper's unless another measures better beyond the interval, says why netx cannot run it,
    and records the best rule netx would run beside it."""
    art = target.lower(small_graph(seed=8, n_h=30), {"scale": "auto"})
    q, port = art.quantization, art.portability
    errors = {k: v for k, v in q["calibration"]["errors"].items() if v is not None}
    assert {"global", "per-layer", "fine"} <= set(errors)
    second = q["calibration"]["significance"]
    best = min(errors, key=errors.get)
    if best != "global" and errors[best] < errors["global"]:
        mine, paper = second["agreement"][best], second["agreement"]["global"]
        assert q["calibration"]["chosen"] == (best if mine["low"] > paper["high"] else "global")
    else:
        assert q["calibration"]["chosen"] == "global"
    assert not port["netx_runnable"] and "refDelay 2" in port["line"] and port["line"].startswith(
        "not runnable by netx as written")
    assert port["best_netx_rule"]["rule"] == "global"       # one exponent, 0: all netx needs of the rule
    assert port["best_netx_rule"]["error"] == errors["global"]


def test_tau_syn_longer_than_tau_mem_is_fine_on_loihi():
    graph = small_graph(seed=9)
    for name in ("hidden", "out"):
        op = graph.node(name)
        op.tau_syn, op.tau_mem = op.tau_mem.copy(), op.tau_syn.copy()   # tau_syn 60 ms > tau_mem 6 ms
    art = target.lower(graph, {"scale": "global"})
    assert art.network.layers[1].i_decay < art.network.layers[1].v_decay
    assert art.validation["timing_exact"] and art.validation["quantized_params_exact"]


def test_check_in_stream_mode_and_overflow_split():
    graph = small_graph(order="spytorch", seed=10)
    x, labels = _x(3, batch=8), np.random.default_rng(1).integers(0, 5, 8)
    rec = target.check(graph, x, labels, {"scale": "global", "stream": True})
    assert rec.details["mode"] == "stream" and rec.samples == 8
    assert [s.key for s in rec.stages] == ["ir_quantized", "emulator_wide", "emulator"]
    assert [s.cause for s in rec.stages] == ["weights", "decays", "saturation"] and rec.causes["other"] is None
    assert rec.details["overflow"] == {"q_wrap": 0, "u_wrap": 0, "v_clip": 0} and rec.causes["saturation"] == 0
