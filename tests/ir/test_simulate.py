"""The reference simulator against traces computed by hand from the node equations (snncc/ir/nodes.py)."""

import math

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.ir import LIF, LSTM, Dense, Graph, Input, Output, Readout, simulate, validate


def one_neuron(w=1.0, delay=0, tau_syn=0.01, tau_mem=0.02, dt=0.001, threshold=1.0, reset="zero",
               refractory=1, discretisation="exp", bias=None, bias_placement="current"):
    g = Graph(dt)
    g.add("x", Input(1))
    g.add("w", Dense(np.array([[w]])))
    g.add("n", LIF(1, tau_syn, tau_mem, threshold, reset=reset, refractory=refractory,
                   discretisation=discretisation, bias=bias, bias_placement=bias_placement))
    g.add("o", Output(1))
    g.connect("x", "w", delay=delay)
    g.connect("w", "n")
    g.connect("n", "o")
    return validate(g)


def trace(g, x):
    r = simulate(g, np.asarray(x, float).reshape(-1, 1), record="all")
    return r.current["n"][0, :, 0], r.voltage["n"][0, :, 0], r.spikes["n"][0, :, 0]


def test_single_neuron_trace_by_hand():
    dt, ts, tm = 0.001, 0.01, 0.02
    a, b = math.exp(-dt / ts), math.exp(-dt / tm)
    g = one_neuron(w=0.6, tau_syn=ts, tau_mem=tm, dt=dt)
    x = [1, 0, 0, 0, 0]
    cur, vol, spk = trace(g, x)
    i_exp, v_exp, s_exp = [], [], []
    i = v = 0.0
    for t in range(5):
        i = a * i + 0.6 * x[t]
        v = b * v + i
        s = v > 1.0
        if s:
            v = 0.0
        i_exp.append(i), v_exp.append(v), s_exp.append(float(s))
    np.testing.assert_allclose(cur, i_exp, rtol=0, atol=1e-15)
    np.testing.assert_allclose(vol, v_exp, rtol=0, atol=1e-15)
    # hand numbers: I0 = .6, V0 = .6; I1 = .6a, V1 = .6b + .6a = 1.1138... > 1 -> spike at t = 1;
    # the current keeps charging V after the reset: V4 = 1.0168... > 1 -> spike again at t = 4
    assert spk.tolist() == s_exp == [0, 1, 0, 0, 1]
    assert vol[1] == 0.0 and vol[2] == pytest.approx(0.6 * a * a)


def test_threshold_is_strict():
    # no leak to speak of (exp(-1e-18) == 1.0): V0 = 1.0 exactly, which is not > 1.0
    _, vol, spk = trace(one_neuron(w=1.0, tau_syn=1e6, tau_mem=1e6, dt=1e-12), [1, 0])
    assert vol[0] == 1.0 and spk[0] == 0.0
    assert spk[1] == 1.0  # V1 = 2.0


def test_reset_subtract_keeps_the_excess():
    _, vol, spk = trace(one_neuron(w=2.5, tau_syn=1e6, tau_mem=1e6, dt=1e-12, reset="subtract"), [1, 0, 0])
    # I stays 2.5: V0 = 2.5 -> spike, 1.5; V1 = 1.5 + 2.5 = 4 -> spike, 3.0; V2 = 5.5 -> 4.5
    assert spk.tolist() == [1, 1, 1]
    np.testing.assert_allclose(vol, [1.5, 3.0, 4.5], atol=1e-9)


def test_refractory_holds_voltage_for_r_minus_1_steps():
    _, vol, spk = trace(one_neuron(w=5.0, tau_syn=1e6, tau_mem=1e6, dt=1e-12, refractory=3), [1, 0, 0, 0, 0, 0])
    # constant I = 5: spike at 0, held at 0 for steps 1 and 2, V3 = 5 -> spike, held 4, 5
    assert spk.tolist() == [1, 0, 0, 1, 0, 0]
    assert vol.tolist()[:3] == [0.0, 0.0, 0.0]


def test_refractory_one_is_no_refractory_period():
    _, _, spk = trace(one_neuron(w=5.0, tau_syn=1e6, tau_mem=1e6, dt=1e-12, refractory=1), [1, 0, 0, 0])
    assert spk.tolist() == [1, 1, 1, 1]


def test_edge_delay_shifts_the_response():
    x = [1, 0, 0, 0, 0, 0]
    _, v0, _ = trace(one_neuron(w=0.1, delay=0), x)
    _, v2, _ = trace(one_neuron(w=0.1, delay=2), x)
    np.testing.assert_allclose(v2[2:], v0[:-2], atol=1e-15)
    assert v2[0] == v2[1] == 0.0


def test_euler_discretisation_uses_one_minus_dt_over_tau():
    dt, ts, tm = 1e-4, 5e-3, 2e-2
    cur, vol, _ = trace(one_neuron(w=0.3, tau_syn=ts, tau_mem=tm, dt=dt, discretisation="euler"), [1, 0, 0])
    a, b = 1 - dt / ts, 1 - dt / tm
    np.testing.assert_allclose(cur, [0.3, 0.3 * a, 0.3 * a * a], atol=1e-15)
    np.testing.assert_allclose(vol, [0.3, 0.3 * b + 0.3 * a, (0.3 * b + 0.3 * a) * b + 0.3 * a * a], atol=1e-15)


def test_bias_on_current_and_on_voltage():
    dt, ts, tm = 1e-3, 1e-2, 2e-2
    a, b = math.exp(-dt / ts), math.exp(-dt / tm)
    cur, vol, _ = trace(one_neuron(w=0.0, tau_syn=ts, tau_mem=tm, dt=dt, bias=0.1, bias_placement="current"), [0, 0])
    np.testing.assert_allclose(cur, [0.1, 0.1 * a + 0.1], atol=1e-15)
    cur, vol, _ = trace(one_neuron(w=0.0, tau_syn=ts, tau_mem=tm, dt=dt, bias=0.1, bias_placement="voltage"), [0, 0])
    np.testing.assert_allclose(cur, [0, 0], atol=0)
    np.testing.assert_allclose(vol, [0.1, 0.1 * b + 0.1], atol=1e-15)


def test_recurrent_pair_by_hand():
    # a drives b (delay 1), b drives a back (delay 1); no leak; threshold 1; weights 1.5
    g = Graph(1e-12)
    g.add("x", Input(2))
    g.add("w_in", Dense(np.array([[1.5, 0.0], [0.0, 0.0]])))
    g.add("pop", LIF(2, 1e6, 1e6, 1.0))
    g.add("w_rec", Dense(np.array([[0.0, 1.5], [1.5, 0.0]])))
    g.add("o", Output(2))
    g.connect("x", "w_in")
    g.connect("w_in", "pop")
    g.connect("pop", "w_rec", delay=1)
    g.connect("w_rec", "pop")
    g.connect("pop", "o")
    validate(g)
    x = np.zeros((5, 2))
    x[0, 0] = 1
    r = simulate(g, x, record="all")
    s = r.spikes["pop"][0]
    # t0: I_a = 1.5 -> a spikes. t1: I_a = 1.5, V_a = 1.5 -> a; I_b = 1.5 (from a at t0) -> b spikes
    assert s[:, 0].tolist() == [1, 1, 1, 1, 1]
    assert s[:, 1].tolist() == [0, 1, 1, 1, 1]
    np.testing.assert_allclose(r.current["pop"][0, 2], [3.0, 3.0], atol=1e-9)


def test_float32_and_float64_agree_on_a_random_rsnn():
    from snncc.frontends.builders import snn_graph

    rng = np.random.default_rng(0)
    g = snn_graph(rng.normal(0, 0.6, (8, 20)), rng.normal(0, 0.5, (20, 5)), rng.normal(0, 0.2, (20, 20)),
                  dt=0.005, tau_syn=0.006, tau_mem=0.06, order="loihi")
    x = (rng.random((3, 60, 8)) < 0.2).astype(np.float32)
    r64 = simulate(g, x, dtype=torch.float64)
    r32 = simulate(g, x, dtype=torch.float32)
    assert r32.output.dtype == np.float32 and r64.output.dtype == np.float64
    agree = float(np.mean(r64.output == r32.output.astype(np.float64)))
    assert agree > 0.99


def test_readouts_decide_ties_to_the_lowest_index():
    g = Graph(1e-3)
    g.add("x", Input(3, signal="analog"))
    g.add("r", Readout(3, mode="spike_count"))
    g.add("o", Output(3))
    g.connect("x", "r")
    g.connect("r", "o")
    validate(g)
    x = np.array([[[0, 1, 1], [0, 1, 1]]], float)
    assert simulate(g, x).prediction.tolist() == [1]
    g.node("r").mode = "last"
    assert simulate(g, np.array([[[3, 0, 3], [0, 2, 2]]], float)).prediction.tolist() == [1]
    g.node("r").mode = "membrane_max"
    assert simulate(g, np.array([[[3, 0, 3], [0, 2, 2]]], float)).prediction.tolist() == [0]


def test_voltage_port_feeds_a_non_spiking_integrator_readout():
    g = Graph(1e-3)
    g.add("x", Input(2))
    g.add("w", Dense(np.eye(2)))
    g.add("li", LIF(2, 0.01, 0.02, np.inf))
    g.add("r", Readout(2, mode="membrane_max"))
    g.add("o", Output(2))
    g.connect("x", "w")
    g.connect("w", "li")
    g.connect("li", "r", port="voltage")
    g.connect("r", "o")
    validate(g)
    x = np.zeros((4, 2))
    x[0] = [1, 0]
    x[1] = [0, 1]
    x[2] = [0, 1]
    r = simulate(g, x, record="all")
    assert r.spikes["li"].sum() == 0
    assert r.prediction.tolist() == [1]
    np.testing.assert_array_equal(r.output, r.voltage["li"])


def test_lstm_node_equals_torch_lstm():
    torch.manual_seed(0)
    lstm = torch.nn.LSTM(3, 5, batch_first=True).double()
    g = Graph(0.025)
    g.add("x", Input(3, signal="analog"))
    g.add("l", LSTM(lstm.weight_ih_l0.detach().numpy(), lstm.weight_hh_l0.detach().numpy(),
                    lstm.bias_ih_l0.detach().numpy(), lstm.bias_hh_l0.detach().numpy()))
    g.add("o", Output(5))
    g.connect("x", "l")
    g.connect("l", "o")
    validate(g)
    x = torch.randn(2, 7, 3, dtype=torch.float64)
    expected, _ = lstm(x)
    np.testing.assert_allclose(simulate(g, x).output, expected.detach().numpy(), rtol=1e-12, atol=1e-12)


def test_input_width_and_nan_are_refused():
    from snncc.errors import SnnccError

    g = one_neuron()
    with pytest.raises(SnnccError, match="channels"):
        simulate(g, np.zeros((3, 2)))
    with pytest.raises(SnnccError, match="NaN"):
        simulate(g, np.full((3, 1), np.nan))


def test_subtract_reset_integrator_with_infinite_threshold_stays_finite():
    _, vol, spk = trace(one_neuron(w=0.5, threshold=np.inf, reset="subtract"), [1, 1, 0])
    assert np.all(np.isfinite(vol)) and spk.sum() == 0


def test_integer_unit_weights_take_float32_products_with_the_same_bits(monkeypatch):
    """Weights that are integers times 2**-7 (as a graph quantized in chip units) and a recurrent layer large enough
    for ``EXACT_MIN_SIZE`` multiply their spikes in float32 (``snncc.exact_products``): every record equals the
    float64 run's bit for bit; the input layer's inputs (not spikes: 0.5) and float32 runs keep their own path."""
    import importlib

    sim = importlib.import_module("snncc.ir.simulate")     # the module, not the function snncc.ir exports

    rng = np.random.default_rng(3)
    g = Graph(0.001)
    g.add("x", Input(40))
    g.add("w", Dense(rng.integers(-60, 61, (300, 40)) * 2.0 ** -7))
    g.add("n", LIF(300, 0.005, 0.02, 1.0, reset="subtract"))
    g.add("r", Dense(rng.integers(-20, 21, (300, 300)) * 2.0 ** -7))
    g.add("o", Output(300))
    g.connect("x", "w")
    g.connect("w", "n")
    g.connect("n", "r", delay=1)
    g.connect("r", "n")
    g.connect("n", "o")
    validate(g)
    x = (rng.random((3, 60, 40)) < 0.3) * np.where(rng.random((3, 60, 40)) < 0.5, 1.0, 0.5)
    taken = sim._Runner(g, np.dtype(np.float64), "all").p["r"][0]
    assert isinstance(taken, sim.ExactProduct) and taken.units_t is not None
    fast = simulate(g, x, record="all")
    monkeypatch.setattr(sim, "EXACT_MIN_SIZE", 1 << 40)
    plain = simulate(g, x, record="all")
    assert fast.spikes["n"].any() and not fast.spikes["n"].all()
    for a, b in [(fast.spikes, plain.spikes), (fast.voltage, plain.voltage), (fast.current, plain.current),
                 (fast.outputs, plain.outputs)]:
        assert all(a[k].tobytes() == b[k].tobytes() for k in b)


def _two_layer_with_delays():
    """Input -> a (recurrent through a delay-3 edge) -> b, with a also read by b through a delay-2 edge."""
    rng = np.random.default_rng(5)
    g = Graph(0.001)
    g.add("x", Input(6))
    g.add("wa", Dense(rng.normal(0.6, 0.4, (8, 6))))
    g.add("a", LIF(8, 0.005, 0.02, 1.0))
    g.add("ra", Dense(rng.normal(0, 0.5, (8, 8))))
    g.add("wb", Dense(rng.normal(0.5, 0.4, (5, 8))))
    g.add("b", LIF(5, 0.005, 0.02, 1.0, reset="subtract"))
    g.add("o", Output(5))
    g.connect("x", "wa")
    g.connect("wa", "a")
    g.connect("a", "ra", delay=3)
    g.connect("ra", "a")
    g.connect("a", "wb", delay=2)
    g.connect("wb", "b")
    g.connect("b", "o")
    return validate(g)


def test_voltage_and_population_records_are_the_full_runs_parts():
    """record "voltage" keeps spikes and post-reset voltages (no currents), ``populations`` keeps only those LIFs:
    both equal the "all" run's arrays bit for bit (a step is released only after its last delayed reader)."""
    g = _two_layer_with_delays()
    x = (np.random.default_rng(6).random((3, 40, 6)) < 0.4).astype(float)
    full = simulate(g, x, record="all")
    assert full.spikes["a"].any() and full.spikes["b"].any()
    part = simulate(g, x, record="voltage")
    assert part.current == {} and part.voltage.keys() == full.voltage.keys()
    for k in full.voltage:
        assert part.voltage[k].tobytes() == full.voltage[k].tobytes()
        assert part.spikes[k].tobytes() == full.spikes[k].tobytes()
    only = simulate(g, x, record="spikes", populations=["b"])
    assert list(only.spikes) == ["b"] and only.spikes["b"].tobytes() == full.spikes["b"].tobytes()
    assert only.outputs["o"].tobytes() == full.outputs["o"].tobytes()
    with pytest.raises(SnnccError, match="not a LIF population"):
        simulate(g, x, record="spikes", populations=["wb"])


def test_a_population_left_out_records_nothing():
    g = _two_layer_with_delays()
    x = (np.random.default_rng(7).random((2, 30, 6)) < 0.4).astype(float)
    only = simulate(g, x, record="all", populations=["a"])
    assert list(only.spikes) == list(only.voltage) == list(only.current) == ["a"]
