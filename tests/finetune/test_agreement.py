"""Fine-tuning's statistics (the one agreement rule of snncc.measure.agreement, paired accuracy difference), the
teacher's records, task-like inputs."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.measure.agreement import argmax_agreement, decided, wilson_interval
from snncc.finetune.engine import paired_difference
from snncc.finetune.ste import spike


def test_wilson_interval_known_values():
    low, high = wilson_interval(80, 100)
    assert low == pytest.approx(0.7111, abs=1e-4) and high == pytest.approx(0.8666, abs=1e-4)
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == 1.0     # exact endpoints
    with pytest.raises(ValueError):
        wilson_interval(0, 0)


def test_clear_winner_rule_leaves_ties_and_silence_out():
    ref = np.array([[3, 1, 0], [2, 2, 0], [0, 0, 0], [0, 5, 1]])
    other = np.array([[3, 0, 0], [2, 0, 0], [1, 0, 0], [0, 0, 9]])
    assert decided(ref).tolist() == [True, False, False, True]
    a = argmax_agreement(ref, other)
    assert (a.agreeing, a.decided, a.samples, a.ties, a.silent) == (1, 2, 4, 1, 1) and a.share == 0.5
    none = argmax_agreement(np.zeros((3, 2)), np.zeros((3, 2)))
    assert none.share is None and none.low is None and "undefined" in none.text()    # never reported as 100 %


def test_paired_difference_of_accuracies():
    labels = np.zeros(100, int)
    a = np.zeros(100, int)
    b = np.zeros(100, int)
    b[:10] = 1                      # b wrong on 10 samples where a is right
    d, lo, hi = paired_difference(a, b, labels)
    assert d == pytest.approx(0.10) and lo < 0.10 < hi and lo > 0


def test_spike_is_exact_and_has_a_surrogate_gradient():
    import torch

    v = torch.tensor([99.0, 100.0, 101.0], dtype=torch.float64, requires_grad=True)
    theta = torch.tensor(100.0, dtype=torch.float64, requires_grad=True)
    s = spike(v, theta)
    assert s.tolist() == [0.0, 0.0, 1.0]          # strict: v == theta does not fire
    s.sum().backward()
    assert torch.all(v.grad > 0) and theta.grad < 0
    assert spike(v.detach(), theta.detach(), strict=False).tolist() == [0.0, 1.0, 1.0]


def test_teacher_pre_reset_voltage_for_subtract_reset():
    from snncc.finetune.teacher import run_teacher
    from tests.finetune.test_engine import tiny_graph

    g = tiny_graph("subtract")
    x = (np.random.default_rng(0).random((3, 30, 6)) < 0.4).astype(np.uint8)
    pops = tuple(n for n, op in g.items() if type(op).__name__ == "LIF")
    t = run_teacher(g, x, pops)
    from snncc.ir.simulate import simulate

    res = simulate(g, x, record="all")
    for p in pops:
        s = t.spikes[p].astype(bool)
        # where it fired, the pre-reset voltage was above threshold (1.0); after a subtract reset V = V_pre - 1
        assert np.all(t.voltage[p][s] > 1.0)
        np.testing.assert_allclose(t.voltage[p][s] - 1.0, np.asarray(res.voltage[p])[s], rtol=1e-5, atol=1e-6)
    assert t.counts.shape == (3, 3)


def test_task_like_braille_inputs():
    from snncc.data.nir_letters import NIR_LETTERS, nir_braille_inputs

    x, y = nir_braille_inputs(14, seed=3)
    x2, y2 = nir_braille_inputs(14, seed=3)
    assert x.shape == (14, 256, 12) and x.dtype == np.uint8 and set(np.unique(x)) <= {0, 1}
    assert np.array_equal(x, x2) and np.array_equal(y, y2)
    assert set(y.tolist()) <= set(range(len(NIR_LETTERS))) and x.sum() > 0


def test_validation_and_held_out_follow_the_training_samples():
    """--finetune-samples 256 builds 640 samples, not 1,756: the other parts scale, with their floors."""
    from snncc.finetune.inputs import MIN_HELD_OUT, MIN_VALIDATION, model_split, synthetic_sizes
    from snncc.frontends.builders import snn_graph

    assert synthetic_sizes(2048) == (500, 1000) and synthetic_sizes(256) == (MIN_VALIDATION, MIN_HELD_OUT)
    assert synthetic_sizes(8192) == (2000, 4000)
    rng = np.random.default_rng(0)
    g = snn_graph(rng.normal(0, 0.6, (6, 10)), rng.normal(0, 0.5, (10, 3)), None, dt=0.005, tau_syn=0.006,
                  tau_mem=0.06, metadata={"recording_length_s": 0.05})
    split = model_split(g, samples=256)
    assert (split.train.size, split.validation.size, split.held_out.size) == (256, 128, 256)
    assert split.x.shape == (640, 10, 6)
