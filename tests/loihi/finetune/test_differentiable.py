"""Loihi's differentiable arithmetic equals the bit-exact emulator on the integers it exports, spike for
spike and state for state, on the real NIR graphs and on random networks (overflow included)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from snncc.frontends import LoadOptions, load_model
from snncc.targets.loihi.checks.exactness import lead_steps, pad
from snncc.targets.loihi.emulation.emulator import emulate
from snncc.targets.loihi.finetune.differentiable import DifferentiableLoihi
from snncc.targets.loihi.lowering.lower import lower_model
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.options import LoihiOptions

from tests.loihi.helpers import random_network

NIR = "tests/data/nir/"
STEPS = 48


def _perturb(student: DifferentiableLoihi, seed: int, size: float = 3.0) -> None:
    """Move every shadow by a random amount (several register units), as training would."""
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for p in student.parameters():
            if p.numel():
                p.add_((torch.rand(p.shape, generator=g, dtype=p.dtype) * 2 - 1) * size * (1 + p.abs().mean()) / 10)
    student.project()


def _assert_equal_to_emulator(student: DifferentiableLoihi, x: np.ndarray, active: bool = True) -> None:
    net = student.export()
    xp = pad(x, student.lead)
    ref = emulate(net, xp, record="all")
    with torch.no_grad():
        run = student.run_chip(student.drive(torch.as_tensor(x)), record=True)
        fused = student.run_fused(student.drive(torch.as_tensor(x)))
    assert not active or any(ref.spikes[i].any() for i in run.spikes), "the test network is silent"
    for i in run.spikes:
        np.testing.assert_array_equal(np.asarray(run.spikes[i]), ref.spikes[i])
        np.testing.assert_array_equal(np.asarray(run.current[i]), ref.current[i])
        np.testing.assert_array_equal(np.asarray(run.voltage[i]), ref.voltage[i])
        np.testing.assert_array_equal(np.asarray(fused.spikes[i]), ref.spikes[i])


def _lowered(name: str, rule: str, reset: str | None):
    g = load_model(NIR + name, LoadOptions(dt=1e-4, reset=reset))
    return lower_model(g, LoihiOptions(scale=rule, allow_reset_change=True), t_sample=STEPS)


@pytest.mark.parametrize("name,rule,reset", [
    ("braille_noDelay_noBias_subtract.nir", "per-layer", "subtract"),
    ("braille_zero_2023.nir", "per-layer", None),        # current biases: always-on axon and compartment
    ("braille_zero_2023.nir", "fine", None),             # per-synapse exponents
    ("braille_zero_2023.nir", "global", None),
])
def test_forward_equals_emulator_on_real_graphs_after_training_steps(name, rule, reset):
    low = _lowered(name, rule, reset)
    names = [c.lif for c in low.layers]
    student = DifferentiableLoihi(low.network, names, low.timing_record.shifts, STEPS)
    x = (np.random.default_rng(3).random((3, STEPS, low.network.input_width)) < 0.1).astype(np.uint8)
    _assert_equal_to_emulator(student, x)          # as lowered
    _perturb(student, 1)
    _assert_equal_to_emulator(student, x)          # after "training"
    student.swap_decays(0)
    _assert_equal_to_emulator(student, x)


@pytest.mark.parametrize("seed", [0, 2, 7, 9])   # networks active on these inputs
@pytest.mark.parametrize("kwargs", [{}, {"big": True}, {"split_exponents": True, "profiles": True},
                                    {"recurrent": False, "per_synapse_delays": False}])
def test_forward_equals_emulator_on_random_networks(seed, kwargs):
    net = random_network(seed, **kwargs)
    student = DifferentiableLoihi(net, ["hidden", "out"], {}, net.t_sample)
    x = (np.random.default_rng(seed).random((2, net.t_sample, net.input_width)) < 0.3).astype(np.uint8)
    _assert_equal_to_emulator(student, x)
    _perturb(student, seed)
    _assert_equal_to_emulator(student, x, active=False)
    if kwargs.get("big"):
        ov = emulate(student.export(), x).overflow
        assert ov["q_wrap"] + ov["u_wrap"] + ov["v_clip"] > 0, "the big network should overflow"


def test_fused_loop_gives_the_step_graphs_values_and_gradients():
    names = ["lif1.lif", "lif2"]
    steps = 20
    low = lower_model(load_model(NIR + "braille_zero_2023.nir", LoadOptions(dt=1e-4)), LoihiOptions(scale="per-layer"),
                      t_sample=steps)
    x = torch.as_tensor((np.random.default_rng(0).random((3, steps, 12)) < 0.2).astype(np.float64))
    force = {names[0]: torch.as_tensor((np.random.default_rng(1).random((3, steps, 38)) < 0.2).astype(np.float64))}
    grads = []
    for fused in (False, True):
        for f in (None, force):
            st = DifferentiableLoihi(low.network, names, low.timing_record.shifts, steps, fused=fused)
            _perturb(st, 2)
            run = st(x, force=f)
            loss = (run.counts ** 2).sum() + sum((v ** 2).sum() for v in run.voltage.values()) * 1e-2 \
                + sum(s.sum() for s in run.spikes.values())
            loss.backward()
            grads.append({k: p.grad.clone() for k, p in st.named_parameters() if p.grad is not None})
    for a, b in ((grads[0], grads[2]), (grads[1], grads[3])):
        assert a.keys() == b.keys() and a
        for k in a:
            torch.testing.assert_close(a[k], b[k], rtol=1e-9, atol=1e-9)


def test_export_keeps_the_format():
    low = _lowered("braille_zero_2023.nir", "per-layer", None)
    names = [c.lif for c in low.layers]
    st = DifferentiableLoihi(low.network, names, low.timing_record.shifts, STEPS)
    _perturb(st, 5, size=30.0)
    out = st.export()
    for a, b in zip(out.layers[1:], low.network.layers[1:]):
        assert np.ndim(a.v_th_mant) == np.ndim(b.v_th_mant) and np.ndim(a.i_decay) == np.ndim(b.i_decay)
        assert np.array_equal(np.asarray(a.wgt_exp), np.asarray(b.wgt_exp)) and np.array_equal(a.delay, b.delay)
        assert a.ref_delay == b.ref_delay and a.always_on == b.always_on and a.kind == b.kind
        w = np.asarray(a.weight)
        assert w.dtype == np.asarray(b.weight).dtype and np.all(w % 2 == 0) and w.min() >= -256 and w.max() <= 254
        m = a.model_n
        assert np.all(np.asarray(a.weight)[m:] == 0)            # nothing reaches an always-on source
    assert not np.array_equal(out.layers[1].weight, low.network.layers[1].weight)
    # one bias term stays one column value per neuron, the original network is untouched
    assert low.network.layers[1].weight is not out.layers[1].weight


def test_sources_keep_firing_when_the_threshold_rises():
    """Raising the threshold above the always-on compartment's bias would silence it: export re-derives it."""
    low = _lowered("braille_zero_2023.nir", "per-layer", None)
    names = [c.lif for c in low.layers]
    st = DifferentiableLoihi(low.network, names, low.timing_record.shifts, STEPS)
    with torch.no_grad():
        st.vth[0].shadow.mul_(3.0)
    x = (np.random.default_rng(3).random((2, STEPS, 12)) < 0.1).astype(np.uint8)
    _assert_equal_to_emulator(st, x)
    res = emulate(st.export(), pad(x, st.lead), record="all")
    src = res.spikes[1][:, :, low.network.layers[1].model_n:]
    assert src.all(), "the always-on compartment must fire on every step"


def test_a_register_per_profile_never_adds_profiles():
    net = random_network(0, profiles=True)
    st = DifferentiableLoihi(net, ["hidden", "out"], {}, net.t_sample)
    _perturb(st, 0)
    out = st.export()
    for field in ("v_th_mant", "i_decay", "v_decay"):
        assert len(np.unique(getattr(out.layers[1], field))) <= len(np.unique(getattr(net.layers[1], field)))


def test_unknown_parameter_kind_is_one_line():
    net = LoihiNetwork([LoihiLayer("in", "input", 2), LoihiLayer("o", "dense", 1, weight=np.zeros((1, 2), np.int16),
                                                                  v_th_mant=10)], t_sample=4)
    from snncc.errors import SnnccError

    with pytest.raises(SnnccError, match="unknown parameter kinds"):
        DifferentiableLoihi(net, ["o"], {}, 4, learn=("weights", "gains"))
