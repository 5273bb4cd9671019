"""Parameter counts of the paper's models and the RSNN forward pass in the authors' order."""


import numpy as np
import pytest
import torch

from snncc.models import SNNConfig, SpikingClassifier, count_trainable
from snncc.models.surrogate import spike
from snncc.training.trainer import build_model
from snncc_test_helpers import authors_loop


def test_parameter_counts_equal_the_papers():
    assert count_trainable(build_model("rsnn", input_copies=2)) == 236_700
    assert count_trainable(build_model("lstm")) == 225_975
    assert count_trainable(build_model("elstm", n_inputs=24)) == 236_919
    # FFSNN: the same without the 450 x 450 recurrent matrix
    assert count_trainable(build_model("ffsnn", input_copies=2)) == 48 * 450 + 450 * 28


def _surrogate(model):
    return lambda v: spike(v, model.config.scale)


def _small_rsnn(recurrent=True, seed=0):
    torch.manual_seed(seed)
    m = SpikingClassifier(SNNConfig(n_hidden=40, n_outputs=7, recurrent=recurrent, input_copies=2, order="spytorch"))
    m.reset_parameters(fwd_weight_scale=4.0, weight_scale_factor=0.5)
    return m.double()


def _inputs(seed=1, batch=3, steps=60):
    g = torch.Generator().manual_seed(seed)
    return (torch.rand(batch, steps, 24, generator=g, dtype=torch.float64) < 0.3).double()


@pytest.mark.parametrize("recurrent", [True, False])
def test_forward_equals_authors_loop_spike_for_spike(recurrent):
    model = _small_rsnn(recurrent)
    x = _inputs()
    s_out, s_hid = model(x)
    ref_out, ref_hid = authors_loop(model.tile_inputs(x), model.w_in, model.w_out, model.v_rec,
                                    model.alpha, model.beta, _surrogate(model))
    assert s_hid.sum() > 50 and s_out.sum() > 5, "the test needs spiking activity in both layers"
    assert torch.equal(s_hid, ref_hid)
    assert torch.equal(s_out, ref_out)


def test_gradients_equal_authors_loop_and_the_reset_is_detached():
    x = _inputs()
    labels = torch.tensor([0, 3, 5])

    def grads(forward):
        model = _small_rsnn()
        out, hid = forward(model)
        loss = torch.nn.functional.cross_entropy(out.sum(1), labels) + 1e-3 * hid.sum()
        loss.backward()
        return [p.grad.clone() for p in (model.w_in, model.w_out, model.v_rec)]

    ours = grads(lambda m: m(x))
    authors = grads(lambda m: authors_loop(m.tile_inputs(x), m.w_in, m.w_out, m.v_rec, m.alpha, m.beta, _surrogate(m)))
    attached = grads(lambda m: authors_loop(m.tile_inputs(x), m.w_in, m.w_out, m.v_rec, m.alpha, m.beta,
                                            _surrogate(m), detach_reset=False))
    for g_ours, g_auth in zip(ours, authors):
        assert torch.count_nonzero(g_ours) > 0
        torch.testing.assert_close(g_ours, g_auth, rtol=1e-10, atol=1e-12)
    # a reset inside the gradient would change them: the comparison above can fail
    assert any(not torch.allclose(a, b) for a, b in zip(ours, attached))


def test_fast_sigmoid_surrogate_is_non_zero_near_threshold():
    scale = 5.0
    mthr = torch.tensor([-0.5, -0.01, 0.0, 0.01, 0.5, 3.0], dtype=torch.float64, requires_grad=True)
    s = spike(mthr, scale)
    assert s.tolist() == [0, 0, 0, 1, 1, 1]      # strict: exactly at threshold is no spike
    s.sum().backward()
    expected = 1.0 / (scale * mthr.detach().abs() + 1.0) ** 2
    torch.testing.assert_close(mthr.grad, expected)
    assert mthr.grad[2] == 1.0 and mthr.grad[1] > 0.9 and mthr.grad[-1] < 0.02


def test_membrane_near_threshold_gets_gradient_without_spiking():
    """A neuron that never spikes but comes close to threshold still passes gradient to its inputs."""
    torch.manual_seed(0)
    m = SpikingClassifier(SNNConfig(n_inputs=1, input_copies=1, n_hidden=1, n_outputs=1, recurrent=False)).double()
    with torch.no_grad():
        m.w_in.fill_(0.04)     # steady state V = 0.04 / (1 - alpha) / (1 - beta) = 0.88 < 1
        m.w_out.fill_(1.0)
    x = torch.ones(1, 40, 1, dtype=torch.float64)
    out, hid = m(x)
    assert hid.sum() == 0
    hid.sum().backward()
    assert m.w_in.grad.abs().item() > 0


def _late_silent_events(n_per_class=24, n_classes=3, steps=80, seed=0):
    """Class c fires its own 8 channels early (steps 10..40); the recording ends in 10 silent steps."""
    rng = np.random.default_rng(seed)
    y = np.repeat(np.arange(n_classes), n_per_class)
    x = (rng.random((y.size, steps, 24)) < 0.02).astype(np.uint8)
    for i, c in enumerate(y):
        x[i, 10:40, 8 * c:8 * c + 8] |= (rng.random((30, 8)) < 0.3).astype(np.uint8)
    x[:, steps - 10:] = 0
    return torch.from_numpy(x), torch.from_numpy(y)


def test_elstm_event_initialisation_keeps_the_architecture_and_learns(tmp_path):
    from snncc.training.training_set import TrainingData
    from snncc.training.pipeline import TrainRequest, train

    model = build_model("elstm", n_inputs=24)
    model.init_for_events(270)
    assert count_trainable(model) == 236_919 and not model.lstm.bias_hh_l0.any()
    h = 228
    assert torch.equal(model.lstm.bias_ih_l0[:h], -model.lstm.bias_ih_l0[h:2 * h])
    assert model.lstm.bias_ih_l0[h:2 * h].min() >= 0 and model.lstm.bias_ih_l0[h:2 * h].max() <= np.log(269)
    x, y = _late_silent_events()
    data = TrainingData(x, y, {"synthetic": True}, "toy")
    res = train(TrainRequest(kind="elstm", data="toy", output=str(tmp_path / "e.pt"), epochs=4, batch_size=8,
                             device="cpu"), data=data)
    losses = [e["loss"] for e in res.epochs]
    assert res.parameters == 236_919
    assert losses[-1] < 0.7 * np.log(3) and res.history["test_accuracy"] >= 0.8
