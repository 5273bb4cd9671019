"""The LIF spike rule fields (max_spikes, fire_test): defaults are today's semantics, bit for bit;
other values follow the loop in nodes.LIF's docstring; files and validation carry them."""

import zipfile

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir import LIF, Dense, Graph, Input, Output, simulate, validate
from snncc.ir.serialize import load_graph, save_graph
from snncc.ir.validate import refuse_spike_rules


def net(w, *, threshold=1.0, reset="subtract", max_spikes=1, fire_test=">", tau_mem=1e30):
    """x -> Dense(w) -> LIF without leak (alpha 0 exactly: tau_syn = dt; beta 1 exactly) -> out."""
    g = Graph(1.0)
    g.add("x", Input(1))
    g.add("w", Dense(np.array([[w]])))
    g.add("n", LIF(1, tau_syn=1.0, tau_mem=tau_mem, threshold=threshold, reset=reset,
                   discretisation="euler", max_spikes=max_spikes, fire_test=fire_test))
    g.add("o", Output(1))
    g.connect("x", "w")
    g.connect("w", "n")
    g.connect("n", "o")
    return validate(g)


def by_loop(drive, theta, m, test, reset):
    """The docstring's rule as a literal loop (V += drive; fire while the test holds, at most m)."""
    v, spikes, volts = 0.0, [], []
    for d in drive:
        v += d
        n = 0
        while n < m and (v >= theta if test == ">=" else v > theta):
            n += 1
            v -= theta
        if n and reset == "zero":
            v = 0.0
        spikes.append(float(n)), volts.append(v)
    return spikes, volts


@pytest.mark.parametrize("m", [1, 3, 31])
@pytest.mark.parametrize("test", [">", ">="])
@pytest.mark.parametrize("reset", ["subtract", "zero"])
def test_counts_and_voltages_follow_the_loop(m, test, reset):
    rng = np.random.default_rng(m)
    drive = np.round(rng.uniform(-1.0, 9.0, 60) * 4) / 4          # quarters: exact sums, V = k*theta happens
    drive[:3] = [2.0, 1.0, 4.0]                                     # exact multiples of theta
    r = simulate(net(1.0, threshold=1.0, reset=reset, max_spikes=m, fire_test=test), drive.reshape(-1, 1),
                 record="all")
    spikes, volts = by_loop(drive, 1.0, m, test, reset)
    np.testing.assert_array_equal(r.spikes["n"][0, :, 0], spikes)
    np.testing.assert_array_equal(r.voltage["n"][0, :, 0], volts)
    assert max(spikes) == min(m, max(spikes))
    if m > 1:
        assert max(spikes) > 1                                      # the case is exercised


def test_defaults_equal_the_standard_rule_bit_for_bit():
    rng = np.random.default_rng(0)
    x = (rng.random((4, 50, 1)) < 0.3).astype(float)
    base = simulate(net(1.37), x, record="all")
    explicit = simulate(net(1.37, max_spikes=1, fire_test=">"), x, record="all")
    for a, b in ((base.spikes, explicit.spikes), (base.voltage, explicit.voltage)):
        assert all(np.array_equal(a[k], b[k]) for k in a)
    assert LIF(1, 1.0, 1.0, 1.0).standard_spikes


def test_ge_fires_where_gt_does_not():
    drive = np.array([1.0, 0.0]).reshape(-1, 1)
    gt = simulate(net(1.0, fire_test=">"), drive, record="spikes").spikes["n"][0, :, 0].tolist()
    ge = simulate(net(1.0, fire_test=">="), drive, record="spikes").spikes["n"][0, :, 0].tolist()
    assert gt == [0.0, 0.0] and ge == [1.0, 0.0]


def test_counts_reach_the_next_dense_as_multiples():
    g = Graph(1.0)
    g.add("x", Input(1))
    g.add("w", Dense(np.array([[5.0]])))
    g.add("a", LIF(1, 1.0, 1e30, 1.0, reset="subtract", discretisation="euler", max_spikes=31, fire_test=">="))
    g.add("w2", Dense(np.array([[0.25]])))
    g.add("b", LIF(1, 1.0, 1e30, 100.0, reset="subtract", discretisation="euler"))
    g.add("o", Output(1))
    for u, v in (("x", "w"), ("w", "a"), ("a", "w2"), ("w2", "b"), ("b", "o")):
        g.connect(u, v)
    r = simulate(validate(g), np.array([[1.0], [0.0]]), record="all")
    assert r.spikes["a"][0, :, 0].tolist() == [5.0, 0.0]
    assert r.voltage["b"][0, 0, 0].item() == 1.25


def test_validation_refuses_bad_rules():
    with pytest.raises(SnnccError, match="max_spikes"):
        validate(net(1.0, max_spikes=0))
    with pytest.raises(SnnccError, match="fire_test"):
        validate(net(1.0, fire_test="=>"))


def test_refuse_spike_rules_names_the_population():
    refuse_spike_rules(net(1.0), "Loihi")
    with pytest.raises(SnnccError) as err:
        refuse_spike_rules(net(1.0, max_spikes=31, fire_test=">="), "Loihi")
    assert "up to 31 per step on V >= threshold" in str(err.value) and err.value.field == "node 'n'"


def test_files_carry_the_rule_and_omit_defaults(tmp_path):
    save_graph(net(1.0), tmp_path / "a.snnir")
    with zipfile.ZipFile(tmp_path / "a.snnir") as zf:
        text = zf.read("graph.json").decode()
    assert "max_spikes" not in text and "fire_test" not in text    # unchanged files for unchanged graphs
    g = net(1.0, max_spikes=31, fire_test=">=")
    save_graph(g, tmp_path / "b.snnir")
    back = load_graph(tmp_path / "b.snnir").node("n")
    assert (back.max_spikes, back.fire_test) == (31, ">=")
    assert load_graph(tmp_path / "a.snnir").node("n").standard_spikes


def test_jetson_and_nir_export_refuse_a_multi_spike_graph(tmp_path):
    from snncc.exporters.nir import graph_to_nir
    from snncc.targets.jetson.plan import plan_graph

    g = net(1.0, max_spikes=31, fire_test=">=")
    for call in (lambda: plan_graph(g), lambda: graph_to_nir(g)):
        with pytest.raises(SnnccError, match="at most one spike per step"):
            call()
    plan_graph(net(1.0))
