"""Current biases on Loihi: always-on sources carry them exactly (targets/loihi/lowering/bias_sources.py).

A bias on the current (Dense bias, or a LIF bias placed on the current) from IR step k is a synapse
from a source that spikes every step; compile's own check (validate_lowering) proves that the
lowered network, run with float parameters, equals the IR spike for spike in every layer.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snncc.errors import InternalError, SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.passes.current_bias import current_biases
from snncc.targets.loihi import lower_model
from snncc.targets.loihi.lowering import bias_sources
from snncc.targets.loihi.bundle.read import read_bundle
from snncc.targets.loihi.bundle.write import write_bundle
from snncc.targets.loihi.emulation.emulator import emulate, reference_run
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.checks.exactness import validate_lowering
from snncc.targets.loihi.options import LoihiOptions


def biased_graph(seed=0, refractory=2, d_in=(1, 0), d_rec=(1, 1), d_out=(1, 0), lif_bias=True, n_in=6, n_h=10, n_out=4,
                 per_neuron=False):
    """input -d-> w_in(b) -d-> hidden(current bias) <-> w_rec(b) ; hidden -d-> w_out(b) -d-> out -> readout.

    Each ``d_*`` is (delay into the Dense, delay out of it): a Dense bias starts at the second.
    ``per_neuron``: the hidden layer draws its threshold and time constants per neuron.
    """
    rng = np.random.default_rng(seed)
    g = Graph(0.005, name="biased", metadata={"recording_length_s": 40 * 0.005})
    lif = dict(tau_syn=0.006, tau_mem=0.05, threshold=1.0, refractory=refractory)
    hidden_lif = dict(lif, tau_syn=rng.uniform(0.004, 0.01, n_h), tau_mem=rng.uniform(0.03, 0.08, n_h),
                      threshold=rng.uniform(0.8, 1.2, n_h)) if per_neuron else lif
    g.add("input", Input(width=n_in))
    g.add("w_in", Dense(weight=rng.normal(0, 0.7, (n_h, n_in)), bias=rng.normal(0.05, 0.1, n_h)))
    g.add("hidden", LIF(n=n_h, bias=rng.normal(0.02, 0.05, n_h) if lif_bias else None, bias_placement="current",
                        **hidden_lif))
    g.add("w_rec", Dense(weight=rng.normal(0, 0.2, (n_h, n_h)), bias=rng.normal(0.0, 0.05, n_h)))
    g.add("w_out", Dense(weight=rng.normal(0, 0.6, (n_out, n_h)), bias=rng.normal(0.1, 0.1, n_out)))
    g.add("out", LIF(n=n_out, **lif))
    g.add("readout", Readout(width=n_out))
    g.add("output", Output(width=n_out))
    g.connect("input", "w_in", delay=d_in[0])
    g.connect("w_in", "hidden", delay=d_in[1])
    g.connect("hidden", "w_rec", delay=d_rec[0])
    g.connect("w_rec", "hidden", delay=d_rec[1])
    g.connect("hidden", "w_out", delay=d_out[0])
    g.connect("w_out", "out", delay=d_out[1])
    g.connect("out", "readout")
    g.connect("readout", "output")
    return g


def _lower_and_check(graph, **options):
    low = lower_model(graph, LoihiOptions(**{"timing": "exact", **options}))
    rec = validate_lowering(low.trained, low.order, low.quantized, low.network, low.layers,
                            low.timing_record.shifts, low.timing_record.output_shift, batch=3)
    return low, rec


def test_current_biases_group_by_first_step():
    g = biased_graph(d_in=(1, 0), d_rec=(0, 1))
    terms = current_biases(g, "hidden")
    assert [t.start for t in terms] == [0, 1]
    assert terms[0].origins == ("hidden", "w_in") and terms[1].origins == ("w_rec",)
    np.testing.assert_allclose(terms[0].vector, g.node("hidden").bias + g.node("w_in").bias)


@pytest.mark.parametrize("refractory", [1, 2, 3])
def test_biased_network_lowers_exactly_and_sources_are_laid_out(refractory):
    low, rec = _lower_and_check(biased_graph(refractory=refractory))
    assert rec.timing_exact and rec.quantized_params_exact and rec.kernel_exact
    net = low.network
    # first layer: one always-on axon per start step (hidden: starts 0 and 1)
    assert net.layers[0].always_on == 2 and net.input_width == 6 and net.layers[0].n == 8
    # the hidden layer carries refDelay compartments for the output layer's single bias term
    hidden = net.layers[1]
    assert hidden.always_on == refractory and hidden.model_n == 10
    assert np.all(hidden.weight[10:] == 0) and np.all(hidden.weight_rec[10:] == 0) and np.all(hidden.weight_rec[:, 10:] == 0)
    assert np.all(hidden.bias[10:] * 2**hidden.bias_exp > hidden.v_th_mant * 64)
    # their synapses into the output layer have consecutive delays
    d = np.broadcast_to(np.asarray(net.layers[2].delay), net.layers[2].weight.shape)
    assert sorted(set(d[0, 10:].tolist())) == list(range(int(d[0, 10]), int(d[0, 10]) + refractory))
    # counts of the output layer exclude nothing (the last layer never has sources)
    assert net.layers[-1].always_on == 0
    res = emulate(net, (np.random.default_rng(1).random((4, 40, 6)) < 0.1).astype(np.uint8), record="all")
    assert 0 < res.spikes[1][..., :10].mean() < 0.5 and res.counts.sum() > 0   # the check compared real activity


@pytest.mark.parametrize("layer, first_source", [(1, 6), (2, 10)])   # input axons; hidden compartments
@pytest.mark.parametrize("off_by", [-1, 1])
def test_the_compile_check_catches_a_bias_source_one_step_off(layer, first_source, off_by):
    """The exactness check has teeth: a bias arriving one step early or late is an error."""
    low = lower_model(biased_graph(), LoihiOptions(timing="exact", scale="global"))   # one exponent: delays 1 and 2 apart
    target_layer = low.network.layers[layer]
    d = np.array(np.broadcast_to(np.asarray(target_layer.delay), target_layer.weight.shape))
    d[:, first_source:] = np.maximum(d[:, first_source:] + off_by, 0)
    target_layer.delay = d
    with pytest.raises(InternalError, match="check failed"):
        validate_lowering(low.trained, low.order, low.quantized, low.network, low.layers,
                          low.timing_record.shifts, low.timing_record.output_shift, batch=3)


def test_always_on_sources_deliver_exactly_from_the_first_biased_step():
    """One source feeding a neuron with full current decay: u[t] = w_chip from step D + 1 on, 0 before."""
    for repeats, shift, start in ((1, 1, 0), (2, 3, 1), (3, 2, 4)):
        pre = LoihiLayer("pre", "dense", 1, weight=np.zeros((1, 1), np.int16), v_th_mant=100, ref_delay=repeats)
        post = LoihiLayer("post", "dense", 1, weight=np.zeros((1, 1), np.int16), v_th_mant=2**17 - 1,
                          i_decay=4096, v_decay=4096)
        bias_sources.attach(pre, post, shift, [(start, np.array([10]))])
        net = LoihiNetwork([LoihiLayer("in", "input", 1), pre, post], t_sample=20)
        res = reference_run(net, np.zeros((1, 20, 1), np.uint8), record="all")
        u = res.current[2][0, :, 0]
        first = shift + start
        assert np.all(u[:first] == 0) and np.all(u[first:] == 10 * 64), (repeats, u)
        fired = res.spikes[1][0, :, 1:]   # every source fires at steps 0, r, 2r, ... (r = refDelay)
        assert fired.shape[1] == repeats and np.all(fired == (np.arange(20) % repeats == 0)[:, None])


def test_bias_from_a_delayed_dense_starts_late_and_paper_timing_still_lowers():
    low, rec = _lower_and_check(biased_graph(d_out=(0, 3), lif_bias=False))
    assert rec.timing_exact
    low, rec = _lower_and_check(biased_graph(), timing="paper")
    assert rec.timing_exact and rec.quantized_params_exact


def test_bias_sources_count_towards_the_scale_and_are_recorded():
    g = biased_graph()
    g.node("w_out").bias = np.full(4, 3.0)   # larger than every weight: it sets w_scale
    low, _ = _lower_and_check(g, scale="global")
    assert low.quant_record.w_scale == int(256 // 3.0)
    proj = {p.dense: p for p in low.quant_record.projections}
    assert proj["w_out"].bias_starts == [0] and proj["w_out"].bias_max_error is not None
    assert proj["w_rec"].bias_starts == []


def test_bundle_round_trip_keeps_the_sources_and_the_emulator_adds_the_axons(tmp_path):
    low, _ = _lower_and_check(biased_graph())
    path = tmp_path / "b.net"
    write_bundle(low.network, path)
    back = read_bundle(path)
    assert [lay.always_on for lay in back.layers] == [lay.always_on for lay in low.network.layers]
    x = (np.random.default_rng(3).random((2, 30, 6)) < 0.2).astype(np.uint8)
    a, b = emulate(low.network, x), emulate(back, x)
    np.testing.assert_array_equal(a.output_spikes, b.output_spikes)
    full = np.concatenate([x, np.ones((2, 30, 2), np.uint8)], axis=2)
    with pytest.raises(SnnccError, match="channels"):
        emulate(back, full)   # the user gives the model's channels; the axons are the driver's job


def test_reader_refuses_a_source_count_as_large_as_the_layer(tmp_path):
    import h5py

    low, _ = _lower_and_check(biased_graph())
    path = tmp_path / "b.net"
    write_bundle(low.network, path)
    with h5py.File(path, "r+") as f:
        del f["layer/1/alwaysOn"]
        f["layer/1/alwaysOn"] = np.int64(99)
    with pytest.raises(SnnccError, match="alwaysOn"):
        read_bundle(path)


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 1000), refractory=st.integers(1, 3),
       d_in=st.tuples(st.integers(0, 2), st.integers(0, 2)), d_rec=st.tuples(st.integers(0, 2), st.integers(1, 2)),
       d_out=st.tuples(st.integers(0, 2), st.integers(0, 2)), lif_bias=st.booleans(), per_neuron=st.booleans())
def test_any_delays_and_refractory_periods_lower_exactly(seed, refractory, d_in, d_rec, d_out, lif_bias, per_neuron):
    """validate_lowering raises on any spike mismatch, so passing it is the exactness proof."""
    _, rec = _lower_and_check(biased_graph(seed, refractory, d_in, d_rec, d_out, lif_bias, per_neuron=per_neuron))
    assert rec.timing_exact and rec.quantized_params_exact and rec.kernel_exact


def test_sources_after_a_voltage_biased_layer_get_their_own_threshold():
    """A layer with its own small voltage bias (bias exponent 0) still hosts bias sources for the next
    layer: they get vThMant 1 (one more compartment profile) instead of an impossible mantissa."""
    g = biased_graph(refractory=1, lif_bias=False)
    g.node("w_in").bias = None
    g.node("w_rec").bias = None
    g.node("hidden").bias, g.node("hidden").bias_placement = np.full(10, 0.01), "voltage"
    low, rec = _lower_and_check(g, scale="global")
    hidden = low.network.layers[1]
    assert hidden.always_on == 1 and hidden.bias_exp == 0
    assert np.asarray(hidden.v_th_mant)[-1] == 1 and np.all(np.asarray(hidden.v_th_mant)[:10] > 1)
    assert hidden.bias[-1] * 2**hidden.bias_exp > 64 and rec.timing_exact and rec.quantized_params_exact


def test_auto_scale_leaves_out_a_candidate_that_cannot_be_lowered():
    """Per-layer scales on tiny weights give a threshold mantissa beyond 17 bits: auto says so and keeps
    the rules that lower, instead of failing the compile."""
    from snncc.targets.loihi import target

    g = biased_graph(refractory=1)
    for name in ("w_in", "w_rec"):
        g.node(name).weight *= 1e-4 / np.abs(g.node(name).weight).max()
        g.node(name).bias = None
    g.node("hidden").bias = None
    g.node("w_out").weight *= 200.0 / np.abs(g.node("w_out").weight).max()   # 1/8-range screen flags w_in, w_rec
    art = target.lower(g, {"scale": "auto"})
    q = art.quantization
    assert "per-layer" in q["calibration"]["refused"] and "cannot be lowered" in q["reason"], q["reason"]
    errors = q["calibration"]["errors"]
    assert "global" in errors and "per-layer" not in errors, errors
    # auto takes the candidate with the smallest measured error (never worse than a rule it tried)
    assert q["rule"] == min(errors, key=errors.get) and art.validation["quantized_params_exact"], q["reason"]


@pytest.mark.parametrize("bad", [[1], "x", 1.5, -1, 10_000])
def test_bad_output_shift_in_bundle_metadata_is_one_line(tmp_path, bad):
    import json

    import h5py

    low, _ = _lower_and_check(biased_graph())
    path = tmp_path / "b.net"
    write_bundle(low.network, path)
    with h5py.File(path, "r+") as f:
        meta = json.loads(f["snncc/metadata"][()][0].decode())
        meta["output_shift"] = bad
        del f["snncc/metadata"]
        data = json.dumps(meta).encode()
        f.create_dataset("snncc/metadata", data=np.array([data], dtype=f"S{len(data)}"))
    with pytest.raises(SnnccError, match="output_shift must be an integer"):
        read_bundle(path)
