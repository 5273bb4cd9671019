"""Zoo modules and snncc checkpoints become IR graphs that compute what the module computes."""

import pytest
import numpy as np
import torch

from snncc.frontends import graph_from_object, load_model
from snncc.frontends.checkpoint import save_checkpoint
from snncc.ir import simulate
from snncc.models import LSTMClassifier, LSTMConfig, SNNConfig, SpikingClassifier, count_trainable


@pytest.mark.parametrize("order", ["spytorch", "loihi"])
@pytest.mark.parametrize("recurrent", [True, False])
def test_snn_module_and_ir_agree_spike_for_spike(order, recurrent):
    torch.manual_seed(1)
    m = SpikingClassifier(SNNConfig(n_hidden=30, n_outputs=6, recurrent=recurrent, order=order)).double()
    m.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.3)
    x = (torch.rand(4, 80, 24) < 0.15).double()
    with torch.no_grad():
        out, hid = m(x)
    g = graph_from_object(m)
    r = simulate(g, x.repeat(1, 1, 2), record="spikes")
    assert hid.sum() > 0
    assert np.array_equal(r.spikes["hidden"], hid.numpy()) and np.array_equal(r.output, out.numpy())


def test_lstm_checkpoint_round_trip_predicts_like_the_module(tmp_path):
    torch.manual_seed(2)
    m = LSTMClassifier(LSTMConfig(n_inputs=12, n_hidden=16, n_outputs=27)).double()
    with torch.no_grad():
        m.lstm.bias_ih_l0.normal_()
    save_checkpoint(m, tmp_path / "lstm.pt", {"encoding": "frames"})
    g = load_model(tmp_path / "lstm.pt")
    assert g.metadata["encoding"] == "frames" and g.metadata["model_kind"] == "lstm"
    x = torch.randn(5, 54, 12, dtype=torch.float64)
    with torch.no_grad():
        scores = m(x)
    r = simulate(g, x)
    np.testing.assert_allclose(r.readout, scores.numpy(), rtol=1.3e-6, atol=1e-5)     # torch's float32 tolerances
    assert np.array_equal(r.prediction, scores.argmax(1).numpy())


def test_paper_parameter_counts():
    assert count_trainable(SpikingClassifier(SNNConfig(input_copies=2))) == 236_700
    assert count_trainable(LSTMClassifier(LSTMConfig(n_inputs=12))) == 225_975
    assert count_trainable(LSTMClassifier(LSTMConfig(n_inputs=24, signal="spikes"))) == 236_919


def test_training_bookkeeping_stays_in_the_checkpoint(tmp_path):
    m = SpikingClassifier(SNNConfig(n_hidden=6, n_outputs=3))
    save_checkpoint(m, tmp_path / "ck.pt", {"split_assignment": "t" * 5000, "threshold": 1})
    g = load_model(tmp_path / "ck.pt")
    assert "split_assignment" not in g.metadata and g.metadata["threshold"] == 1
