"""snncc -> NIR -> snncc is exact; a plain NIR import of an export simulates the same network."""

import json

import nir
import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.exporters.nir import export_nir, graph_to_nir
from snncc.frontends import LoadOptions, load_model
from snncc.frontends.builders import lstm_graph, snn_graph
from snncc.frontends.nir import graph_from_nir
from snncc.ir import save_graph
from snncc.ir.serialize import load_graph
from snncc.ir.simulate import simulate

IMPORT_KEYS = {"import_notes", "source_file", "source_sha256"}


def assert_same_ir(a, b):
    assert (a.name, a.dt) == (b.name, b.dt)
    assert list(a) == list(b)
    assert a.edges() == b.edges()
    for name, op in a.items():
        other = b.node(name)
        assert type(op) is type(other), name
        assert op.scalars() == other.scalars(), name
        arrays, others = op.arrays(), other.arrays()
        assert arrays.keys() == others.keys(), name
        for key in arrays:
            assert arrays[key].dtype == others[key].dtype
            np.testing.assert_array_equal(arrays[key], others[key], err_msg=f"{name}.{key}")
    strip = lambda m: {k: v for k, v in m.items() if k not in IMPORT_KEYS}  # noqa: E731
    assert strip(a.metadata) == strip(b.metadata)


def _rsnn(order, recurrent=True, seed=0, n_hidden=20):
    rng = np.random.default_rng(seed)
    return snn_graph(rng.normal(0, 1.5, (48, n_hidden)), rng.normal(0, 1, (n_hidden, 7)),
                     rng.normal(0, 0.3, (n_hidden, n_hidden)) if recurrent else None,
                     dt=0.005, tau_syn=0.006, tau_mem=0.06, order=order, input_copies=2,
                     metadata={"classes": list("ABCDEFG"), "recording_length_s": 1.35})


@pytest.mark.parametrize("order", ["spytorch", "loihi"])
@pytest.mark.parametrize("recurrent", [True, False])
def test_round_trip_is_exact(tmp_path, order, recurrent):
    g = _rsnn(order, recurrent)
    report = export_nir(g, tmp_path / "m.nir")
    back = load_model(tmp_path / "m.nir")
    assert_same_ir(g, back)
    if order == "spytorch":
        assert back.delay("input", "w_in") == 2 and back.node("hidden").refractory == 2
        assert any("refractory periods (" in line and "2 steps" in line for line in report.not_honoured)
        if recurrent:
            assert back.delay("hidden", "w_rec") == 3
    stored = nir.read(str(tmp_path / "m.nir"), type_check=False)
    assert "snnTorch's convention" in stored.metadata["snncc_dt_convention"]
    assert json.loads(stored.metadata["snncc"])["dt"] == 0.005
    assert sum(isinstance(n, nir.Delay) for n in stored.nodes.values()) == (3 if recurrent else 2)


def test_round_trip_of_subtract_reset_and_nonspiking_and_nominal_step(tmp_path):
    g = _rsnn("loihi", seed=3)
    g.node("hidden").reset = "subtract"
    g.node("hidden").discretisation = "euler"
    out = g.node("out")
    out.threshold = np.full(out.n, np.inf)
    g.nx.edges["out", "readout"]["port"] = "voltage"
    g.node("readout").mode = "membrane_max"
    g.node("hidden").bias = np.linspace(-0.1, 0.1, g.node("hidden").n)
    g.node("hidden").bias_placement = "voltage"
    for step in (None, 1e-4):
        export_nir(g, tmp_path / "m.nir", step=step)
        assert_same_ir(g, load_model(tmp_path / "m.nir"))


def test_plain_nir_import_of_an_export_simulates_identically():
    """Without snncc's record (what another tool sees), the loihi-order export is the same network."""
    g = _rsnn("loihi", seed=1)
    nir_graph, _ = graph_to_nir(g)
    del nir_graph.metadata["snncc"]
    plain = graph_from_nir(nir_graph)  # dt from the graph metadata key 'dt'
    assert plain.dt == g.dt and plain.node("hidden").discretisation == "euler"
    assert plain.delay("hidden", "w_rec") == 1  # the Delay node, not an extra implicit step
    x = (np.random.default_rng(2).random((4, 150, 48)) < 0.1).astype(float)
    a, b = simulate(g, x, record="spikes"), simulate(plain, x, record="spikes")
    assert a.spikes["hidden"].sum() > 50
    np.testing.assert_array_equal(np.asarray(a.spikes["hidden"]), np.asarray(b.spikes["hidden"]))
    np.testing.assert_array_equal(np.asarray(a.output), np.asarray(b.output))


def test_lif_current_bias_is_exported_on_its_dense(tmp_path):
    """NIR has no LIF current bias: the exporter moves it into the Dense that feeds the LIF with delay 0 (the
    same term), and the file simulates as the graph did."""
    g = _rsnn("loihi", seed=4)
    hidden = g.node("hidden")
    hidden.bias = np.linspace(-0.2, 0.3, hidden.n)
    hidden.bias_placement = "current"
    export_nir(g, tmp_path / "m.nir")
    back = load_model(tmp_path / "m.nir")
    assert back.node("hidden").bias is None and g.node("hidden").bias is not None     # the input graph is kept
    x = (np.random.default_rng(5).random((4, 120, 48)) < 0.1).astype(float)
    a, b = simulate(g, x, record="spikes"), simulate(back, x, record="spikes")
    assert a.spikes["hidden"].sum() > 50
    np.testing.assert_allclose(np.asarray(a.spikes["hidden"]), np.asarray(b.spikes["hidden"]))
    np.testing.assert_array_equal(np.asarray(a.output), np.asarray(b.output))


def test_edited_export_is_refused():
    g = _rsnn("spytorch")
    nir_graph, _ = graph_to_nir(g)
    nir_graph.edges.remove(("hidden", "delay_hidden_w_out"))
    nir_graph.edges.append(("hidden", "w_out"))
    with pytest.raises(SnnccError, match="does not match the snncc record"):
        graph_from_nir(nir_graph)


def test_lstm_cannot_be_exported():
    rng = np.random.default_rng(0)
    g = lstm_graph(rng.normal(size=(16, 3)), rng.normal(size=(16, 4)), None, rng.normal(size=(2, 4)), None,
                   dt=0.005, signal="analog")
    with pytest.raises(SnnccError, match="NIR has no LSTM"):
        graph_to_nir(g)


def test_cli_export_checkpoint_then_compile_back(tmp_path, small_rsnn_checkpoint, capsys):
    from nir_graphs import run_cli

    out = tmp_path / "m.nir"
    code, stdout, stderr = run_cli(["export", small_rsnn_checkpoint, "--to", "nir", "-o", out], capsys)
    assert code == 0, stderr
    assert "dt convention" in stdout and "NOT honour" in stdout and "refractory periods" in stdout
    code, stdout, stderr = run_cli(["compile", out, "--target", "ir", "-o", tmp_path / "m.snnir"], capsys)
    assert code == 0, stderr
    assert "snncc export record found" in stderr
    assert_same_ir(load_model(small_rsnn_checkpoint), load_graph(tmp_path / "m.snnir"))
    code, stdout, _ = run_cli(["export", small_rsnn_checkpoint, "-o", tmp_path / "j.nir", "--json"], capsys)
    assert code == 0 and json.loads(stdout)["dt"] == 0.005


def test_cli_export_spytorch_weights_with_params(tmp_path, authors_weights, th1_params, capsys):
    from nir_graphs import run_cli

    code, _, stderr = run_cli(["export", authors_weights, "--params", th1_params, "-o", tmp_path / "a.nir"], capsys)
    assert code == 0, stderr
    assert_same_ir(load_model(authors_weights, LoadOptions(params=th1_params)), load_model(tmp_path / "a.nir"))


def test_cli_export_refusals_leave_no_file(tmp_path, capsys):
    from nir_graphs import run_cli

    rng = np.random.default_rng(0)
    lstm = tmp_path / "l.snnir"
    save_graph(lstm_graph(rng.normal(size=(16, 3)), rng.normal(size=(16, 4)), None, rng.normal(size=(2, 4)), None,
                          dt=0.005, signal="analog"), lstm)
    for args, rule in ((["export", lstm, "-o", tmp_path / "l.nir"], "NIR has no LSTM"),
                       (["export", lstm, "--to", "onnx", "-o", tmp_path / "l.nir"], "unknown export format")):
        code, _, stderr = run_cli(args, capsys)
        assert code == 2 and rule in stderr and len(stderr.strip().splitlines()) == 1
        assert not (tmp_path / "l.nir").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["l.snnir"]


def test_nir_import_export_import_is_exact(tmp_path):
    """A snnTorch-style graph imported, exported and imported again is the same IR (biases, Euler, delays)."""
    from nir_graphs import BrailleRSNN

    first = graph_from_nir(BrailleRSNN.random(np.random.default_rng(4)).to_nir(), reset="zero-delayed")
    export_nir(first, tmp_path / "again.nir")
    second = load_model(tmp_path / "again.nir")
    assert_same_ir(first, second)


from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n_hidden=st.integers(1, 9), order=st.sampled_from(["spytorch", "loihi"]), recurrent=st.booleans(),
       delays=st.tuples(st.integers(0, 5), st.integers(1, 5), st.integers(0, 5)), refractory=st.integers(1, 4),
       reset=st.sampled_from(["zero", "subtract"]), disc=st.sampled_from(["exp", "euler"]),
       tau=st.floats(0.002, 1.0), step=st.sampled_from([None, 1e-4, 3e-3]), seed=st.integers(0, 2**16))
def test_round_trip_property(tmp_path, n_hidden, order, recurrent, delays, refractory, reset, disc, tau, step, seed):
    rng = np.random.default_rng(seed)
    g = snn_graph(rng.normal(size=(4, n_hidden)), rng.normal(size=(n_hidden, 3)),
                  rng.normal(size=(n_hidden, n_hidden)) if recurrent else None,
                  dt=0.005, tau_syn=tau, tau_mem=tau * 3, order=order, name=f"g{seed}")
    g.set_delay("input", "w_in", delays[0])
    g.set_delay("hidden", "w_out", delays[2])
    if recurrent:
        g.set_delay("hidden", "w_rec", delays[1])
    for name in ("hidden", "out"):
        op = g.node(name)
        op.refractory, op.reset, op.discretisation = refractory, reset, disc
        op.threshold = rng.uniform(0.5, 2.0, op.n)
    nir_graph, _ = graph_to_nir(g, step=step)
    assert_same_ir(g, graph_from_nir(nir_graph))
