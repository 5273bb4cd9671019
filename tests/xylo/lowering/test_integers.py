"""Kernels, identification and rounding of the Xylo lowering, against hand results and the IR."""

import numpy as np
import pytest

from snncc.ir.simulate import simulate
from snncc.rounding import round_with_feedback
from snncc.targets.xylo.lowering import decays as kernels, regression as identify
from snncc.targets.xylo.lowering.integers import choose_gains

from xylo_models import chain


def test_decay_grid_and_nearest_dash():
    assert kernels.grid([0, 1, 2, 3]).tolist() == [0.0, 0.5, 0.75, 0.875]
    assert kernels.nearest_dash([0.75, 0.85, 0.45, 0.7, 0.2]).tolist() == [2, 3, 1, 2, 0]
    assert kernels.neighbour_dashes(0.85) == (2, 3) and kernels.neighbour_dashes(0.75) == (2, 2)


def test_lif_kernel_is_the_ir_response():
    g = chain(np.random.default_rng(0), n_in=1, n_hidden=1, n_out=1, alpha=0.75, beta=0.85, theta=1e9)
    g.node("w_in").weight[:] = 1.0
    g.node("w_rec").weight[:] = 0.0
    x = np.zeros((1, 30, 1))
    x[0, 0, 0] = 1
    v = simulate(g, x, record="all").voltage["hidden"][0, :, 0]
    np.testing.assert_allclose(v, kernels.lif_kernel(0.75, 0.85, np.arange(30)), rtol=1e-12)


def test_two_exponentials_are_exact_when_both_decays_are_on_the_grid():
    fit = kernels.two_exponential(0.75, 0.875, (2, 3))
    assert fit.u == pytest.approx((-8.0, 8.0)) and fit.rho == pytest.approx((0.0, -1.0), abs=1e-12)
    assert fit.drive_error < 1e-12 and fit.reset_error < 1e-12
    off = kernels.two_exponential(0.75, 0.85, (2, 3))
    assert 0 < off.drive_error < 0.05
    assert kernels.best_pairs(0.75, 0.85, 1)[0].dashes == (2, 3)


def test_memoryless_readout_with_exact_kernels_reproduces_the_ir_neuron():
    """V = i1 + i2 with the partial-fraction weights and the reset fed back: the IR LIF, spike for spike."""
    rng = np.random.default_rng(4)
    g = chain(rng, n_in=5, n_hidden=8, n_out=2, alpha=0.75, beta=0.875)
    x = (rng.random((4, 120, 5)) < 0.2).astype(float)
    ref = np.asarray(simulate(g, x, record="spikes").spikes["hidden"])
    fit = kernels.two_exponential(0.75, 0.875, (2, 3))
    w_in, w_rec = g.node("w_in").weight, g.node("w_rec").weight
    i = np.zeros((2, 4, 8))
    s = np.zeros((4, 8))
    got = []
    for t in range(120):
        for k, a in enumerate((0.75, 0.875)):
            i[k] = a * (i[k] + fit.u[k] * (x[:, t] @ w_in.T + s @ w_rec.T) + fit.rho[k] * s)
        s = (i.sum(0) > 1.0).astype(float)
        got.append(s)
    np.testing.assert_array_equal(np.stack(got, 1), ref)
    assert ref.sum() > 50


def test_chip_filter_and_delay():
    z = np.zeros((1, 5, 1))
    z[0, 1, 0] = 4
    assert identify.chip_filter(z, 0.5)[0, :, 0].tolist() == [0, 2, 1, 0.5, 0.25]
    assert identify.delayed(z, 2)[0, :, 0].tolist() == [0, 0, 0, 4, 0]


def test_rounding_with_feedback_beats_nearest_on_the_quadratic_form():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(400, 12)) @ np.diag(rng.uniform(0.2, 2, 12)) + rng.normal(size=(400, 1))  # correlated
    h = a.T @ a
    c = rng.normal(0, 3, 12)
    step = np.full(12, 0.7)
    err = lambda k: float((k * step - c) @ h @ (k * step - c))  # noqa: E731
    near = np.clip(np.round(c / step), -128, 127)
    fb = round_with_feedback(h, c, step)
    assert err(fb) < err(near)
    # with a diagonal form there is nothing to feed back: both round to nearest
    assert round_with_feedback(np.diag(np.diag(h)), c, step).tolist() == near.astype(int).tolist()


def test_identification_recovers_weights_that_explain_the_voltages():
    """On an IR neuron whose decays are on the grid, the regression (ridge towards a wrong prior) moves to
    the kernel solution: the voltages it predicts match the IR's."""
    rng = np.random.default_rng(1)
    g = chain(rng, n_in=4, n_hidden=3, n_out=2, alpha=0.75, beta=0.875)
    x = (rng.random((40, 100, 4)) < 0.2).astype(float)
    r = simulate(g, x, record="all")
    s = np.asarray(r.spikes["hidden"])
    v_pre = np.asarray(r.voltage["hidden"]) + s
    d = identify.design([x, identify.delayed(s, 1)], (0.75, 0.875), v_pre, np.ones(3), 1e9, False)
    fit = kernels.two_exponential(0.75, 0.875, (2, 3))
    exact = np.concatenate([fit.u[0] * g.node("w_in").weight[0], fit.u[0] * g.node("w_rec").weight[0]
                            + fit.rho[0] * np.eye(3)[0],
                            fit.u[1] * g.node("w_in").weight[0], fit.u[1] * g.node("w_rec").weight[0]
                            + fit.rho[1] * np.eye(3)[0]])
    np.testing.assert_allclose(d.features @ exact, v_pre[..., 0].reshape(-1), atol=1e-9)
    [(h, b)] = identify.normal_equations(d, [0])
    y = v_pre[..., 0].reshape(-1)
    prior = exact * 0.5
    c, _ = identify.ridge_towards(h, b, prior, 1e-8)
    assert np.linalg.norm(d.features @ c - y) < 1e-4 * np.linalg.norm(y) < np.linalg.norm(d.features @ prior - y)


def test_normal_equations_summed_by_blocks_equal_the_whole_rows():
    """Blocks of rows (several per design here) give each neuron A^T A and A^T y of its own weighted rows, rows
    under ROW_FLOOR left out."""
    rng = np.random.default_rng(4)
    rows = 2 * identify.ROW_BLOCK + 123
    d = identify.Design(rng.normal(size=(rows, 5)), rng.normal(size=(rows, 3)), rng.random((rows, 3)) ** 3)
    for j, (h, b) in zip([2, 0], identify.normal_equations(d, [2, 0])):
        keep = d.weight[:, j] >= identify.ROW_FLOOR
        assert 0 < keep.sum() < rows
        a = d.features[keep] * d.weight[keep, j, None]
        np.testing.assert_allclose(h, a.T @ a, rtol=1e-12)
        np.testing.assert_allclose(b, a.T @ (d.target[keep, j] * d.weight[keep, j]), rtol=1e-12)


def test_normal_equations_leave_out_the_features_a_block_never_sees():
    """A feature zero on every row of a block (a silent source) is left out of that block's products: H and b
    are the sums over the whole rows all the same, and a feature no block sees has exact zeros in H and b."""
    rng = np.random.default_rng(7)
    rows = 3 * identify.ROW_BLOCK + 77
    f = rng.normal(size=(rows, 6)) * (rng.random((rows, 6)) < 0.5)
    f[:identify.ROW_BLOCK, [1, 4]] = 0.0                               # silent in the first block
    f[identify.ROW_BLOCK:2 * identify.ROW_BLOCK] = 0.0                 # a block where nothing is seen
    f[:, 5] = 0.0                                                      # never seen
    d = identify.Design(f, rng.normal(size=(rows, 2)), rng.random((rows, 2)) ** 3)
    for j, (h, b) in zip([1, 0], identify.normal_equations(d, [1, 0])):
        keep = d.weight[:, j] >= identify.ROW_FLOOR
        a = d.features[keep] * d.weight[keep, j, None]
        np.testing.assert_allclose(h, a.T @ a, rtol=1e-12)
        np.testing.assert_allclose(b, a.T @ (d.target[keep, j] * d.weight[keep, j]), rtol=1e-12)
        assert not np.any(h[5]) and not np.any(h[:, 5]) and b[5] == 0.0
        assert np.all(np.diag(h)[:5] > 0)


def test_a_block_longer_than_row_block_is_summed_whole():
    """``accumulate`` takes its caller's blocks as they come: one longer than ROW_BLOCK gets a buffer of its size."""
    rng = np.random.default_rng(1)
    rows = 2 * identify.ROW_BLOCK + 5
    f, y, w = rng.normal(size=(rows, 4)), rng.normal(size=(rows, 2)), rng.random((rows, 2))
    [(h, b)] = identify.accumulate(iter([(f, y, w)]), [1], 4)
    keep = w[:, 1] >= identify.ROW_FLOOR
    a = f[keep] * w[keep, 1, None]
    np.testing.assert_allclose(h, a.T @ a, rtol=1e-12)
    np.testing.assert_allclose(b, a.T @ (y[keep, 1] * w[keep, 1]), rtol=1e-12)


def test_gains_fill_eight_bits_where_states_allow():
    state = np.array([1000.0, 1000.0, 50.0])
    wmax = [np.array([2.0, 10.0, 2.0])]
    gains, (shift,) = choose_gains(state, wmax)
    # the shift keeps every neuron at >= min(state, 64) chip units per threshold; gains never exceed 127 * 2^s
    assert np.all(gains * wmax[0] <= 127 * 2 ** shift + 1e-9)
    assert gains[2] == 50.0 and gains[0] > gains[1]
