"""bench/speed/bench_xylo_finetune.py compares the fast paths with the former ones; its baselines must compute what the
library computes (identical integers, normal equations equal to float rounding), or its ratios mean nothing."""

from __future__ import annotations

from argparse import Namespace

import numpy as np

from snncc.rounding import round_with_feedback
from snncc.targets.xylo.lowering import regression as identify
from snncc_test_helpers import load_bench


def test_the_baselines_compute_what_the_library_computes():
    bench = load_bench("speed/bench_xylo_finetune")
    ro = bench.rounding(Namespace(forms=4, coefficients=15, repeat=1))
    assert ro["identical_integers"] and ro["speedup"] > 0
    rng = np.random.default_rng(3)
    a = rng.normal(size=(40, 9))
    c = rng.normal(scale=30, size=(3, 9))
    steps, low, high = rng.uniform(0.5, 2, 9), -rng.integers(5, 40, 9), rng.integers(5, 40, 9)
    assert np.array_equal(bench.former_rounding(a.T @ a, c, steps, low, high, last=4),
                          round_with_feedback(a.T @ a, c, steps, low, high, last=4))
    rows = identify.ROW_BLOCK + 500
    d = identify.Design(rng.normal(size=(rows, 6)), rng.normal(size=(rows, 4)), rng.random((rows, 4)) ** 4)
    for (h0, b0), (h1, b1) in zip(bench.per_neuron_normal_equations(d, [3, 1]), identify.normal_equations(d, [3, 1])):
        np.testing.assert_allclose(h1, h0, rtol=1e-12)
        np.testing.assert_allclose(b1, b0, rtol=1e-12)


def test_the_former_arithmetic_is_patched_in_and_restored():
    bench = load_bench("speed/bench_xylo_finetune")
    from snncc.targets.xylo.lowering import integers

    current = identify.hidden_normal_equations, integers.round_with_feedback
    with bench.former_arithmetic():
        assert identify.hidden_normal_equations is bench.former_hidden_normal_equations
        assert integers.round_with_feedback is bench.former_rounding
    assert (identify.hidden_normal_equations, integers.round_with_feedback) == current
    rng = np.random.default_rng(5)
    sources = [(rng.random((6, 50, 3)) < 0.3).astype(np.uint8), (rng.random((6, 50, 4)) < 0.2).astype(np.uint8)]
    v_pre = rng.normal(size=(6, 50, 2))
    former = bench.former_hidden_normal_equations(sources, (0.75, 0.875), v_pre, np.ones(2), 2.0, True)
    for (h0, b0), (h1, b1) in zip(former, identify.hidden_normal_equations(sources, (0.75, 0.875), v_pre, np.ones(2),
                                                                            2.0, True)):
        np.testing.assert_allclose(h1, h0, rtol=1e-12)
        np.testing.assert_allclose(b1, b0, rtol=1e-12)
