"""IR features beyond the paper's models, through both artefacts: refractory > 2 (counters),
subtract reset, biases on current and voltage, Euler decays, a non-spiking integrator read out
through its voltage (membrane_max), delays on every edge kind, a delayed edge into an LSTM."""

from __future__ import annotations

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Dense, Input, Output, Readout
from snncc.ir.simulate import simulate
from snncc.ir.validate import validate
from snncc.targets.jetson import target
from snncc.targets.jetson.standalone_runner import ArtefactRunner

T = 25


def general_snn() -> Graph:
    rng = np.random.default_rng(3)
    g = Graph(0.001, name="general", metadata={"classes": ["a", "b", "c"]})
    g.add("input", Input(width=4))
    g.add("w_in", Dense(weight=rng.normal(0, 1.5, (8, 4)), bias=rng.normal(0, 0.2, 8)))
    g.add("a", LIF(n=8, tau_syn=0.004, tau_mem=rng.uniform(0.01, 0.03, 8), threshold=0.8, reset="subtract",
                   refractory=3, bias=rng.normal(0, 0.1, 8), bias_placement="voltage"))
    g.add("w_rec", Dense(weight=rng.normal(0, 0.6, (8, 8))))
    g.add("w_out", Dense(weight=rng.normal(0, 1.0, (3, 8))))
    g.add("li", LIF(n=3, tau_syn=0.005, tau_mem=0.02, threshold=np.inf, discretisation="euler",
                    bias=np.array([0.01, 0.0, -0.01]), bias_placement="current"))
    g.add("readout", Readout(width=3, mode="membrane_max"))
    g.add("output", Output(width=3))
    g.connect("input", "w_in", delay=2)
    g.connect("w_in", "a")
    g.connect("a", "w_rec", delay=1)
    g.connect("w_rec", "a")
    g.connect("a", "w_out", delay=3)
    g.connect("w_out", "li")
    g.connect("li", "readout", port="voltage")
    g.connect("readout", "output")
    return validate(g)


def delayed_lstm() -> Graph:
    rng = np.random.default_rng(4)
    g = Graph(0.025, name="dlstm")
    g.add("input", Input(width=3, signal="analog"))
    g.add("lstm", LSTM(weight_ih=rng.normal(0, 0.5, (24, 3)), weight_hh=rng.normal(0, 0.5, (24, 6)),
                       bias_ih=rng.normal(0, 0.1, 24), bias_hh=rng.normal(0, 0.1, 24)))
    g.add("fc", Dense(weight=rng.normal(0, 1, (4, 6)), bias=rng.normal(0, 0.1, 4)))
    g.add("readout", Readout(width=4, mode="last"))
    g.add("output", Output(width=4))
    g.connect("input", "lstm", delay=2)
    g.connect("lstm", "fc")
    g.connect("fc", "readout")
    g.connect("readout", "output")
    return validate(g)


def test_general_snn_both_artefacts_match_reference(tmp_path):
    g = general_snn()
    art = target.lower(g, {"time_steps": T})
    art.write(tmp_path / "a")
    assert art.manifest["readout"]["score_output"] == "scores"
    x = (np.random.default_rng(5).random((5, T, 4)) < 0.4).astype(np.float32)
    ref = simulate(g, x.astype(np.float64), record="spikes")
    assert ref.spikes["a"].sum() > 0
    runner = ArtefactRunner(str(tmp_path / "a"), backend="onnxruntime")
    whole, streamed = runner.run(x), runner.stream(x)
    np.testing.assert_allclose(whole["output_values"], np.asarray(ref.output), atol=1e-4)
    np.testing.assert_allclose(streamed["output_values"], np.asarray(ref.output), atol=1e-4)
    np.testing.assert_array_equal(whole["prediction"], np.asarray(ref.prediction))
    np.testing.assert_array_equal(streamed["prediction"], np.asarray(ref.prediction))
    # the refractory counter is real state of the step model
    assert any(s["what"] == "ref" for s in art.manifest["variants"][1]["state"])


def test_lstm_with_a_delayed_input_edge(tmp_path):
    g = delayed_lstm()
    art = target.lower(g, {"time_steps": 12})
    art.write(tmp_path / "l")
    x = np.random.default_rng(6).standard_normal((3, 17, 3)).astype(np.float32)
    ref = simulate(g, x.astype(np.float64))
    runner = ArtefactRunner(str(tmp_path / "l"), backend="onnxruntime")
    np.testing.assert_allclose(runner.run(x)["scores"], np.asarray(ref.readout), atol=1e-5)
    np.testing.assert_allclose(runner.stream(x)["scores"], np.asarray(ref.readout), atol=1e-5)
