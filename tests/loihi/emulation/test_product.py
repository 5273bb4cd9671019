"""The plain statement's synaptic product (``emulator._Product``): integer weights in float32 only where every
partial sum is an exact integer below 2**24 (in units of the weights' common power of two), else float64;
either way the integer sums exactly, spike row by spike row, dense or sparse."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.targets.loihi.emulation import emulator


def _exact(spikes: np.ndarray, w: np.ndarray) -> np.ndarray:
    return spikes.astype(np.int64) @ w.astype(np.int64).T


@pytest.mark.parametrize("shift, mixed, expect", [(0, False, np.float32), (13, False, np.float32),
                                                  (13, True, np.float64)])
def test_float32_only_where_every_sum_is_exact(shift, mixed, expect):
    """Even mantissas times 2**shift, as w_chip: the common power of two keeps the sums small, unless exponents
    differ per synapse (``mixed``: half the synapses at 2**0 with odd weights), when 300 x 127 x 2**13 > 2**24."""
    rng = np.random.default_rng(shift)
    w = (rng.integers(-127, 128, (40, 300)) * 2) << shift
    if mixed:
        w[:, :150] = rng.integers(-63, 64, (40, 150)) * 2 + 1
    product = emulator._Product(w)
    assert product.w_t.dtype == expect
    if expect == np.float32:   # the common power of two is divided out: at least 2 * 2**shift
        assert product.scale >= 2.0 ** (shift + 1)
        assert np.abs(w // int(product.scale)).sum(axis=1).max() < emulator.FLOAT32_EXACT
    for density in (0.02, 0.6):                                     # the sparse and the dense product
        s = (rng.random((5, 300)) < density).astype(np.int64)
        out = product.of(s)
        assert out.dtype == np.float64 and np.array_equal(out, _exact(s, w))


def test_a_sum_past_2_to_24_is_not_taken_in_float32():
    w = np.zeros((2, 600), np.int64)
    w[0] = 2 ** 15 - 1                                              # odd: no common power of two to divide out
    product = emulator._Product(w)
    assert 600 * (2 ** 15 - 1) >= emulator.FLOAT32_EXACT and product.w_t.dtype == np.float64
    s = np.ones((1, 600), np.int64)
    assert np.array_equal(product.of(s), _exact(s, w))


def test_float_weights_stay_float64():
    w = np.random.default_rng(1).normal(size=(3, 7))
    assert emulator._Product(w).w_t.dtype == np.float64


def test_the_float_fallback_is_the_scaled_transpose(monkeypatch):
    """Float weights with no integer units are held as (w * factor).T, copied in row blocks."""
    import snncc.transpose

    monkeypatch.setattr(snncc.transpose, "TRANSPOSE_ROWS", 3)
    w = np.random.default_rng(4).normal(size=(10, 7))
    product = emulator._Product(w, 0.25)
    assert product.w_t.flags.c_contiguous and np.array_equal(product.w_t, (w * 0.25).T)
    s = (np.random.default_rng(5).random((2, 7)) < 0.5).astype(np.float64)
    assert np.allclose(product.of(s), s @ (w * 0.25).T, rtol=1e-14, atol=0)
