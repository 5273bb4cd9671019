"""Malformed graphs are refused naming the node and the rule; graphs survive a file round trip."""

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.frontends.builders import lstm_graph, snn_graph
from snncc.ir import LIF, Dense, Graph, Input, Output, load_graph, save_graph, simulate, validate


def small_rsnn(order="spytorch", seed=0):
    rng = np.random.default_rng(seed)
    return snn_graph(rng.normal(0, 0.5, (6, 10)), rng.normal(0, 0.5, (10, 4)), rng.normal(0, 0.1, (10, 10)),
                     dt=0.005, tau_syn=0.006, tau_mem=0.06, order=order, input_copies=2)


def chain(weight_shape=(3, 2), input_width=2):
    g = Graph(1e-3)
    g.add("x", Input(input_width))
    g.add("w", Dense(np.ones(weight_shape)))
    g.add("n", LIF(weight_shape[0], 0.01, 0.02, 1.0))
    g.add("o", Output(weight_shape[0]))
    g.connect("x", "w")
    g.connect("w", "n")
    g.connect("n", "o")
    return g


def test_valid_graphs_pass():
    validate(small_rsnn())
    validate(chain())


@pytest.mark.parametrize("mutate, match", [
    (lambda g: setattr(g, "dt", None), "no dt"),
    (lambda g: setattr(g, "dt", -1.0), "positive"),
    (lambda g: g.node("w").weight.__setitem__((0, 0), np.nan), "NaN"),
    (lambda g: g.node("w").weight.__setitem__((0, 0), np.inf), "Inf"),
    (lambda g: g.node("n").tau_mem.__setitem__(0, 0.0), "time constants"),
    (lambda g: setattr(g.node("n"), "reset", "sideways"), "reset"),
    (lambda g: setattr(g.node("n"), "refractory", 0), "refractory"),
    (lambda g: setattr(g.node("n"), "discretisation", "rk4"), "discretisation"),
])
def test_bad_parameters_name_node_and_rule(mutate, match):
    g = chain()
    mutate(g)
    with pytest.raises(SnnccError, match=match):
        validate(g)


def test_shapes_that_do_not_chain_are_named():
    g = chain(weight_shape=(3, 5), input_width=2)
    with pytest.raises(SnnccError, match=r"edge x->w.*shapes do not chain"):
        validate(g)


def test_cycle_with_zero_delay_is_refused():
    g = small_rsnn()
    g.set_delay("hidden", "w_rec", 0)
    with pytest.raises(SnnccError, match="delay >= 1"):
        validate(g)


def test_cycle_not_through_a_neuron_is_refused():
    g = Graph(1e-3)
    g.add("x", Input(2))
    g.add("a", Dense(np.eye(2)))
    g.add("b", Dense(np.eye(2)))
    g.add("o", Output(2))
    g.connect("x", "a")
    g.connect("a", "b", delay=1)
    g.connect("b", "a", delay=1)
    g.connect("b", "o")
    with pytest.raises(SnnccError):
        validate(g)


def test_missing_nodes_and_names():
    g = Graph(1e-3)
    with pytest.raises(SnnccError, match="Input"):
        validate(g)
    g.add("x", Input(1))
    with pytest.raises(SnnccError, match="unique"):
        g.add("x", Input(1))
    with pytest.raises(SnnccError, match="does not exist"):
        g.connect("x", "nowhere")


@pytest.mark.parametrize("make", [small_rsnn, lambda: small_rsnn("loihi"),
                                  lambda: lstm_graph(np.ones((8, 3)), np.ones((8, 2)), np.zeros(8), np.ones((4, 2)),
                                                     np.zeros(4), dt=0.025, signal="analog")])
def test_file_round_trip_is_exact_and_deterministic(tmp_path, make):
    g = make()
    save_graph(g, tmp_path / "a.snnir")
    save_graph(g, tmp_path / "b.snnir")
    assert (tmp_path / "a.snnir").read_bytes() == (tmp_path / "b.snnir").read_bytes()
    h = load_graph(tmp_path / "a.snnir")
    assert h.dt == g.dt and h.metadata == g.metadata and h.edges() == g.edges()
    for (n1, op1), (n2, op2) in zip(g.items(), h.items()):
        assert n1 == n2 and type(op1) is type(op2) and op1.scalars() == op2.scalars()
        for key, arr in op1.arrays().items():
            np.testing.assert_array_equal(arr, op2.arrays()[key])
    x = (np.random.default_rng(1).random((2, 20, g.node("input").size)) < 0.3).astype(float)
    assert np.array_equal(np.asarray(simulate(g, x).output), np.asarray(simulate(h, x).output))


def test_damaged_ir_file_is_one_clear_error(tmp_path):
    p = tmp_path / "bad.snnir"
    p.write_bytes(b"PK\x03\x04 not really a zip")
    with pytest.raises(SnnccError, match="not a readable snncc IR file"):
        load_graph(p)


def test_damaged_deflate_data_in_an_ir_file_is_one_clear_error(tmp_path):
    """A member whose compressed bytes are damaged (zlib: invalid block type) is refused like any damage,
    not a zlib.error traceback (found by the loaders' fuzz test)."""
    import zipfile

    good = tmp_path / "good.snnir"
    save_graph(small_rsnn(), good)
    data = bytearray(good.read_bytes())
    with zipfile.ZipFile(good) as zf:
        info = zf.getinfo("graph.json")
    start = info.header_offset + 30 + len(info.filename.encode()) + len(info.extra)
    data[start:start + 4] = b"\xff\xff\xff\xff"         # BFINAL 1, BTYPE 11: a reserved block type
    bad = tmp_path / "bad.snnir"
    bad.write_bytes(bytes(data))
    with pytest.raises(SnnccError, match=r"not a readable snncc IR file \(error\)") as caught:
        load_graph(bad)
    assert caught.value.line().count("\n") == 0
