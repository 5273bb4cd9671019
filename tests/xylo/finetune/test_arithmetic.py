"""Xylo's differentiable arithmetic (targets/xylo/differentiable.py) equals the bit-exact emulator, spike for
spike and state for state, on random specs (saturating, wrapping and multi-spike cases included), and its
gradients flow to every learnable register."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.targets.xylo.finetune.arithmetic import DifferentiableXylo, recurrent_blocks
from snncc.targets.xylo.emulation.emulator import emulate, reference_run
from tests.xylo.networks import random_inputs
from tests.xylo.emulation.test_emulator import spec_for_tests

CASES = [
    dict(seed=1, alias_fraction=0.0),
    dict(seed=2, alias_fraction=0.0, synapse_axis=0, shift_in=3, shift_rec=2, shift_out=3),   # 2-D, small weights
    dict(seed=5, alias_fraction=0.0, shift_in=12, shift_rec=10, shift_out=9, threshold_scale=0.05),  # saturating
    dict(seed=7, alias_fraction=0.0, synapse_axis=1, bias_fraction=1.0, threshold_scale=2.0),
]


def _states(run):
    return {k: v.detach().numpy() for k, v in run.states.items()}


def _forward_equals_the_emulator(spec, seed: int, by_blocks: bool = False):
    x = random_inputs(seed, 6, 40, spec.n_in, 0.5, 15)
    model = DifferentiableXylo(spec, 40, {"hidden": np.arange(spec.n_hidden)}, "out", by_blocks=by_blocks)
    with torch.no_grad():
        run = model(torch.as_tensor(x, dtype=torch.float64), record=True)
    ref = reference_run(spec, x, record=True)
    fast = emulate(spec, x, record=True)
    mine = _states(run)
    assert np.array_equal(mine["output_spikes"], ref.output_spikes)
    assert np.array_equal(ref.output_spikes, fast.output_spikes)
    for name in ("vmem", "isyn", "isyn2", "spikes", "vmem_out", "isyn_out"):
        assert np.array_equal(mine[name], getattr(ref, name)), name
    assert np.array_equal(run.counts.numpy(), ref.counts)
    return run


@pytest.mark.parametrize("knobs", CASES)
def test_forward_equals_the_emulator_state_for_state(knobs):
    run = _forward_equals_the_emulator(spec_for_tests(**knobs), knobs["seed"])
    assert run.spikes["hidden"].max() > 1 or knobs["seed"] != 5      # the saturating case emits multi-spikes


def _in_blocks(spec, k: int):
    """``spec`` with every recurrent weight between neurons of different index mod k set to zero: k blocks that
    no weight joins, interleaved as a replicated network's copies are."""
    n = spec.n_hidden
    same = (np.arange(n)[:, None] % k) == (np.arange(n)[None, :] % k)
    w = np.array(spec.weights_rec)
    w[~same] = 0
    return dataclasses.replace(spec, weights_rec=w)


@pytest.mark.parametrize("knobs", [CASES[0], CASES[1], CASES[2]])
def test_block_by_block_delivery_equals_the_emulator(knobs):
    """A network whose recurrent weights split into blocks (replicas) is delivered block by block: still the
    chip's sums and saturations, state for state."""
    spec = _in_blocks(spec_for_tests(**knobs), 3)
    w = torch.as_tensor(np.atleast_3d(np.asarray(spec.weights_rec, np.float64)))
    blocks = recurrent_blocks(w)
    assert len(blocks) >= 3 and sorted(np.concatenate(blocks).tolist()) == list(range(spec.n_hidden))
    assert all(np.all(b % 3 == b[0] % 3) for b in blocks)
    run = _forward_equals_the_emulator(spec, knobs["seed"], by_blocks=True)
    assert run.spikes["hidden"].max() > 1 or knobs["seed"] != 5


def test_the_saturating_case_really_saturates():
    spec = spec_for_tests(**CASES[2])
    x = random_inputs(5, 6, 40, spec.n_in, 0.5, 15)
    ev = reference_run(spec, x, count=True).events
    assert ev["current_saturations"] > 0 and ev["vmem_saturations"] > 0


def test_export_round_trips_and_gradients_reach_every_register():
    spec = spec_for_tests(seed=1, alias_fraction=0.0)
    model = DifferentiableXylo(spec, 30, {"hidden": np.arange(spec.n_hidden)}, "out")
    same = model.export()
    for name in ("weights_in", "weights_rec", "weights_out", "threshold", "threshold_out", "bias", "bias_out"):
        assert np.array_equal(getattr(same, name), getattr(spec, name)), name
    x = torch.as_tensor(random_inputs(1, 4, 30, spec.n_in, 0.5, 3), dtype=torch.float64)
    run = model(x)
    (run.counts.sum() + run.spikes["hidden"].sum()).backward()
    for kind, params in model.param_groups().items():
        assert params and all(p.grad is not None and torch.isfinite(p.grad).all() for p in params), kind
    assert any(float(p.grad.abs().sum()) > 0 for p in model.param_groups()["weights"])
    with torch.no_grad():
        model.w_rec.add_(0.7)
        model.theta.add_(-0.6)
    moved = model.export()
    ref = reference_run(moved, x.numpy().astype(np.uint8))
    with torch.no_grad():
        assert np.array_equal(model(x).counts.numpy(), ref.counts)


def test_aliases_and_non_positive_thresholds_are_refused():
    with pytest.raises(SnnccError) as e:
        DifferentiableXylo(spec_for_tests(seed=3, alias_fraction=0.5), 10)
    assert e.value.field == "aliases"
    with pytest.raises(SnnccError) as e:
        DifferentiableXylo(spec_for_tests(seed=3, alias_fraction=0.0, negative_thresholds=True), 10)
    assert e.value.field == "threshold"


def test_float32_by_blocks_equals_float64_whole_in_values_and_gradients():
    """The fast path (float32, block by block) computes the same values as float64 over the whole network, and
    the same gradients up to float32 rounding, except on the weights between blocks (zero, and kept zero by a
    student whose layout is kept), which the blocks leave without one."""
    spec = _in_blocks(spec_for_tests(**CASES[0]), 2)
    x = torch.as_tensor(random_inputs(1, 4, 30, spec.n_in, 0.5, 3), dtype=torch.float64)
    runs, grads = [], []
    for dtype, by_blocks in ((torch.float32, True), (torch.float64, False)):
        model = DifferentiableXylo(spec, 30, {"hidden": np.arange(spec.n_hidden)}, "out", dtype=dtype,
                                   by_blocks=by_blocks)
        run = model(x)
        (run.counts.sum() + run.spikes["hidden"].sum() + run.voltage["hidden"].sum()).backward()
        runs.append(run)
        grads.append({name: p.grad.double() for name, p in model.named_parameters() if p.grad is not None})
    fast, exact = runs
    assert fast.counts.dtype == torch.float32 and exact.counts.dtype == torch.float64
    assert torch.equal(fast.counts.double(), exact.counts)
    assert torch.equal(fast.spikes["hidden"].double(), exact.spikes["hidden"])
    n = spec.n_hidden
    between = torch.as_tensor((np.arange(n)[:, None] % 2) != (np.arange(n)[None, :] % 2))
    assert set(grads[0]) == set(grads[1]) >= {"w_in", "w_rec", "w_out", "theta", "bias"}
    for name, g64 in grads[1].items():
        g32 = grads[0][name]
        if name == "w_rec":
            assert not g32[between].any() and g64[between].abs().sum() > 0
            g32, g64 = g32[~between], g64[~between]
        torch.testing.assert_close(g32, g64, rtol=1e-4, atol=1e-4 * float(g64.abs().max()) + 1e-12)
