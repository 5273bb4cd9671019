"""NIR import: snnTorch- and Norse-style graphs equal independent forward-Euler simulations."""

import nir
import numpy as np
import pytest

from nir_graphs import BrailleRSNN, continuous_euler, norse_graph, sparse_inputs
from snncc.errors import SnnccError
from snncc.frontends.nir import graph_from_nir
from snncc.ir.nodes import LIF, Dense, Readout
from snncc.ir.simulate import simulate
from snncc.ir.validate import validate


def _import(nir_graph, **kw):
    return validate(graph_from_nir(nir_graph, **kw))


def _spikes(g, x, name):
    return np.asarray(simulate(g, x, record="spikes").spikes[name])


@pytest.mark.parametrize("form,address", [("subgraph", "dotted"), ("subgraph", "whole"), ("subgraph", "keys"),
                                          ("flat", "dotted")])
def test_snntorch_braille_rsnn_equals_independent_euler(form, address):
    rng = np.random.default_rng(11)
    model = BrailleRSNN.random(rng, n_hidden=38, bias=True, scale=0.6)
    x = sparse_inputs(rng, batch=6, steps=150)
    hidden_ref, out_ref = model.simulate(x, reset="zero")
    assert 0.02 < hidden_ref.mean() < 0.5 and out_ref.sum() > 20  # the comparison is not vacuous

    g = _import(model.to_nir(form=form, address=address))
    assert g.dt == 1e-4 and g.metadata["dt_source"] == "inferred"
    assert any("inferred from the snnTorch convention" in n for n in g.metadata["import_notes"])
    hidden = "lif1" if form == "flat" else "lif1.lif"
    lif = g.node(hidden)
    assert lif.discretisation == "euler" and lif.reset == "zero" and lif.refractory == 1
    np.testing.assert_allclose(lif.decays(g.dt)[0], model.hidden.alpha, rtol=0, atol=1e-12)
    assert g.node("fc1").bias is not None  # the Affine bias stays on the current (Dense bias)
    rec = [u for u, v, d, _ in g.edges() if v != hidden and u == hidden and d == 1]
    assert len(rec) == 1  # recurrent edge: previous step's spikes; feed-forward delay 0
    assert sum(d for *_, d, _ in g.edges()) == 1

    res = simulate(g, x, record="spikes")
    np.testing.assert_array_equal(np.asarray(res.spikes[hidden]), hidden_ref)
    np.testing.assert_array_equal(np.asarray(res.output), out_ref)
    np.testing.assert_array_equal(np.asarray(res.prediction), np.argmax(out_ref.sum(1), axis=1))


def test_forty_neuron_linear_subtract_subgraph_and_flat_same_ir():
    rng = np.random.default_rng(5)
    model = BrailleRSNN.random(rng, n_hidden=40, bias=False, scale=0.6)
    x = sparse_inputs(rng, batch=5, steps=150)
    hidden_ref, out_ref = model.simulate(x, reset="subtract")
    assert hidden_ref.mean() > 0.02 and out_ref.sum() > 20

    flat = _import(model.to_nir(form="flat"), reset="subtract")
    sub = _import(model.to_nir(form="subgraph"), reset="subtract")
    rename = {"lif1.lif": "lif1", "lif1.w_rec": "w_rec"}
    assert [rename.get(n, n) for n in sub] == list(flat)
    assert sorted((rename.get(u, u), rename.get(v, v), d, p) for u, v, d, p in sub.edges()) == sorted(flat.edges())
    for name, op in sub.items():
        other = flat.node(rename.get(name, name))
        assert type(op) is type(other) and op.scalars() == other.scalars()
        for key, arr in op.arrays().items():
            np.testing.assert_array_equal(arr, other.arrays()[key])
    assert isinstance(flat.node("w_rec"), Dense) and flat.node("w_rec").bias is None
    assert flat.node("lif1").reset == "subtract"
    np.testing.assert_array_equal(_spikes(flat, x, "lif1"), hidden_ref)
    np.testing.assert_array_equal(np.asarray(simulate(flat, x).output), out_ref)
    # reset to zero would be a different model: the option matters
    assert not np.array_equal(_spikes(_import(model.to_nir(form="flat")), x, "lif1"), hidden_ref)


def test_norse_style_needs_dt_and_then_matches_continuous_euler():
    rng = np.random.default_rng(2)
    graph = norse_graph(rng)
    with pytest.raises(SnnccError, match=r"try dt=0\.0005 "):
        graph_from_nir(graph)
    dt = 1e-3
    g = _import(graph, dt=dt)
    assert g.metadata["dt_source"] == "--dt"
    x = sparse_inputs(rng, batch=4, steps=100, channels=6, p=0.2)
    ref = continuous_euler(graph.nodes["fc"].weight, graph.nodes["lif"], x, dt)
    assert 0.01 < ref.mean() < 0.6
    out = np.asarray(simulate(g, x).output)
    np.testing.assert_array_equal(out, ref)
    # r and w_in (gain dt^2/(tau_syn*tau_mem) = 0.02) went into the weights; threshold unchanged
    np.testing.assert_allclose(g.node("fc").weight, graph.nodes["fc"].weight * 0.02, rtol=1e-12)
    np.testing.assert_array_equal(g.node("lif").threshold, np.ones(10))


def test_v_leak_is_an_exact_voltage_bias_and_li_output_is_voltage():
    rng = np.random.default_rng(3)
    n_in, n = 4, 5
    dt = 1e-3
    lif = nir.CubaLIF(tau_syn=np.full(n, 4e-3), tau_mem=np.full(n, 2e-2), r=np.full(n, 2.0),
                      v_leak=np.full(n, 0.3), v_threshold=np.ones(n), w_in=np.full(n, 3.0))
    li = nir.LI(tau=np.full(3, 1e-2), r=np.full(3, 10.0), v_leak=np.zeros(3))
    w, w2 = rng.normal(0, 3, (n, n_in)), rng.normal(0, 1, (3, n))
    graph = nir.NIRGraph(nodes={"input": nir.Input(np.array([n_in])), "fc": nir.Linear(w), "lif": lif,
                                "fc2": nir.Linear(w2), "li": li, "output": nir.Output(np.array([3]))},
                         edges=[("input", "fc"), ("fc", "lif"), ("lif", "fc2"), ("fc2", "li"), ("li", "output")],
                         type_check=False)
    g = _import(graph, dt=dt)
    x = sparse_inputs(rng, batch=3, steps=80, channels=n_in, p=0.3)
    spikes = continuous_euler(w, lif, x, dt)
    assert spikes.mean() > 0.01
    v = np.zeros((3, 3))
    expect = []
    for t in range(80):  # LI: tau dv/dt = (v_leak - v) + r*I, I = W2 s
        v = v + dt / 1e-2 * (-v + 10.0 * spikes[:, t] @ w2.T)
        expect.append(v)
    res = simulate(g, x)
    np.testing.assert_allclose(np.asarray(res.output), np.stack(expect, 1), rtol=1e-10, atol=1e-12)
    assert isinstance(g.node("readout"), Readout) and g.node("readout").mode == "membrane_max"
    assert g.node("lif").bias_placement == "voltage"


def test_feed_forward_delay_node_becomes_edge_delay_and_threshold_node():
    rng = np.random.default_rng(4)
    dt = 1e-3
    graph = nir.NIRGraph(nodes={"input": nir.Input(np.array([3])), "d": nir.Delay(np.full(3, 3 * dt)),
                                "fc": nir.Linear(rng.normal(size=(2, 3))), "thr": nir.Threshold(np.full(2, 0.5)),
                                "output": nir.Output(np.array([2]))},
                         edges=[("input", "d"), ("d", "fc"), ("fc", "thr"), ("thr", "output")], type_check=False)
    g = _import(graph, dt=dt)
    assert g.delay("input", "fc") == 3
    x = rng.normal(size=(1, 20, 3))
    want = np.zeros((1, 20, 2))
    want[:, 3:] = (x[:, :-3] @ graph.nodes["fc"].weight.T) > 0.5
    np.testing.assert_array_equal(np.asarray(simulate(g, x).output), want)


@pytest.mark.parametrize("change,rule", [
    (lambda g: g.nodes["lif"].__setattr__("v_reset", np.full(10, 0.1)), "v_reset"),
    (lambda g: g.nodes.__setitem__("d", nir.Delay(np.full(6, 1.5e-3))), "whole number of steps"),
])
def test_refusals(change, rule):
    graph = norse_graph(np.random.default_rng(0))
    change(graph)
    if "d" in graph.nodes:
        graph.edges[:] = [("input", "d"), ("d", "fc"), ("fc", "lif"), ("lif", "output")]
    with pytest.raises(SnnccError, match=rule):
        graph_from_nir(graph, dt=1e-3)


def test_dt_larger_than_a_time_constant_is_refused():
    with pytest.raises(SnnccError, match="exceeds a time constant"):
        graph_from_nir(norse_graph(np.random.default_rng(0)), dt=6e-3)


def test_inconsistent_r_cannot_infer_dt():
    graph = norse_graph(np.random.default_rng(0))
    graph.nodes["lif"].r = np.linspace(50, 60, 10)
    with pytest.raises(SnnccError, match="cannot infer dt"):
        graph_from_nir(graph)


def test_scale_and_flatten_fold_away():
    rng = np.random.default_rng(6)
    w = rng.normal(size=(4, 3))
    lif = nir.LIF(tau=np.full(4, 1e-2), r=np.full(4, 1e-2 / 1e-3), v_leak=np.zeros(4), v_threshold=np.ones(4))
    graph = nir.NIRGraph(nodes={"input": nir.Input(np.array([3])), "flat": nir.Flatten(np.array([3]), start_dim=0),
                                "fc": nir.Linear(w), "s": nir.Scale(np.arange(1.0, 5.0)), "lif": lif,
                                "output": nir.Output(np.array([4]))},
                         edges=[("input", "flat"), ("flat", "fc"), ("fc", "s"), ("s", "lif"), ("lif", "output")],
                         type_check=False)
    g = _import(graph)  # dt inferred from LIF r = tau/dt
    assert g.dt == 1e-3 and list(g) == ["input", "fc", "lif", "readout", "output"]
    np.testing.assert_array_equal(g.node("fc").weight, np.arange(1.0, 5.0)[:, None] * w)
    assert isinstance(g.node("lif"), LIF) and np.all(g.node("lif").decays(g.dt)[0] == 0)


def test_snntorch_late_zero_reset_is_refractory_two():
    rng = np.random.default_rng(8)
    model = BrailleRSNN.random(rng, n_hidden=38, bias=True, scale=0.6)
    x = sparse_inputs(rng, batch=4, steps=150)
    hidden_ref, out_ref = model.simulate(x, reset="zero-delayed")
    g = _import(model.to_nir(), reset="zero-delayed")
    lif = g.node("lif1.lif")
    assert (lif.reset, lif.refractory) == ("zero", 2)
    np.testing.assert_array_equal(_spikes(g, x, "lif1.lif"), hidden_ref)
    np.testing.assert_array_equal(np.asarray(simulate(g, x).output), out_ref)
    immediate, _ = model.simulate(x, reset="zero")
    assert not np.array_equal(immediate, hidden_ref)  # the two snnTorch rules really differ
