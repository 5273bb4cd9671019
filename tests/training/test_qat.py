"""The straight-through fake-quantizer over Loihi's rules, reached through the ``arithmetic`` capability."""

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.models import SNNConfig, SpikingClassifier
from snncc.targets.loihi.lowering import quantize as loihi_pass
from snncc.targets.loihi.arithmetic.straight_through import fake_quantize, quantize_weights
from snncc.training.qat import chip_config, chip_parameters, quantized_forward, target_arithmetic


def loihi_quantization(model):
    return chip_parameters(model, target_arithmetic("loihi")).quantization


def test_rounding_is_half_to_even_and_clipped():
    w_scale = 2
    # W * w_scale / 2 = W: halves round to even, then times 2; +256 clips to 254
    w = torch.tensor([0.5, 1.5, 2.5, -0.5, -1.5, 127.5, 128.0, -128.0, -200.0], dtype=torch.float64)
    assert quantize_weights(w, w_scale).tolist() == [0, 4, 4, 0, -4, 254, 254, -256, -256]


@pytest.mark.parametrize("seed", range(5))
def test_torch_fake_quantizer_equals_the_loihi_pass(seed):
    rng = np.random.default_rng(seed)
    weights = [rng.normal(0, s, size=shape) for s, shape in ((0.2, (48, 30)), (0.1, (30, 30)), (0.3, (30, 7)))]
    # include exact ties: values whose scaled halves end in .5
    weights[0][0, :4] = [0.25, -0.75, 1.25, 0.0]
    max_abs = max(np.abs(w).max() for w in weights)
    ws = loihi_pass.weight_scale(max_abs)
    for w in weights:
        ours = quantize_weights(torch.from_numpy(w), ws).numpy()
        theirs = loihi_pass.quantize_weights(w, ws)
        assert np.array_equal(ours, theirs.astype(np.float64))


def test_straight_through_gradient_is_the_identity():
    w = torch.tensor([0.013, -0.2, 0.37], dtype=torch.float64, requires_grad=True)
    q = fake_quantize(w, 100)
    assert torch.equal(q.detach(), quantize_weights(w.detach(), 100) / 100)
    (q * torch.tensor([1.0, 2.0, 3.0], dtype=torch.float64)).sum().backward()
    assert w.grad.tolist() == [1.0, 2.0, 3.0]


def _model(order="spytorch"):
    torch.manual_seed(0)
    m = SpikingClassifier(SNNConfig(n_hidden=30, n_outputs=7, order=order))
    m.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.5)
    return m.double()


def test_record_uses_the_global_rule():
    m = _model()
    q = loihi_quantization(m)
    max_abs = max(float(p.detach().abs().max()) for p in m.parameters())
    assert q.w_scale == int(np.floor(256 / max_abs))
    assert q.v_th_mant == round(q.w_scale * 1.0)
    assert (q.i_decay, q.v_decay) == (2315, 327)          # th1: dt 5 ms, tau_syn 6 ms, tau_mem 60 ms


@pytest.mark.parametrize("order", ["spytorch", "loihi"])
def test_quantized_forward_is_the_model_with_chip_parameters(order):
    """Fake-quantized pass == the plain model given w_q / w_scale, vThMant / w_scale and the chip's decays."""
    m = _model(order)
    x = (torch.rand(2, 50, 24, generator=torch.Generator().manual_seed(2), dtype=torch.float64) < 0.3).double()
    out_q, hid_q = quantized_forward(m, x)
    q = loihi_quantization(m)
    ref = _model(order)
    with torch.no_grad():
        for p in ref.parameters():
            p.copy_(quantize_weights(p, q.w_scale) / q.w_scale)
    with chip_config(ref, chip_parameters(m, target_arithmetic())):
        assert ref.alpha == pytest.approx((4096 - 2315) / 4096, abs=1e-15)
        assert ref.beta == pytest.approx((4096 - 327) / 4096, abs=1e-15)
        out_r, hid_r = ref(x)
    assert ref.config.threshold == 1.0                     # the context restores the config
    assert hid_q.sum() > 20
    assert torch.equal(out_q, out_r) and torch.equal(hid_q, hid_r)
    # and the float model differs from it (the quantization is not a no-op)
    assert not torch.equal(m(x)[1], hid_q)


def test_qat_gradients_reach_the_float_weights():
    m = _model()
    x = (torch.rand(2, 40, 24, generator=torch.Generator().manual_seed(3), dtype=torch.float64) < 0.3).double()
    out, hid = quantized_forward(m, x)
    (out.sum() + hid.sum()).backward()
    assert all(p.grad is not None and torch.count_nonzero(p.grad) > 0 for p in m.parameters())


def test_all_zero_weights_are_refused():
    m = _model()
    with torch.no_grad():
        for p in m.parameters():
            p.zero_()
    with pytest.raises(SnnccError, match="w_scale"):
        loihi_quantization(m)


def test_a_target_without_arithmetic_is_refused_in_one_line():
    with pytest.raises(SnnccError) as err:
        target_arithmetic("jetson")
    assert err.value.line() == "--target: target 'jetson' offers no differentiable arithmetic to fine-tune through"
