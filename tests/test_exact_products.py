"""Products by small-integer inputs in float32 where every partial sum is exact (``snncc.exact_products``): the same
bits as the float64 product, taken only where the weights are integers times one power of two with row sums below
2**24 and the input is integer-valued and small enough."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snncc.exact_products import FLOAT32_EXACT, ExactProduct, integer_units


def _bits_equal(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 31), exponent=st.integers(-30, 20), top=st.sampled_from([1, 127, 255, 32767]),
       density=st.floats(0.0, 1.0), batch=st.integers(1, 6))
def test_float32_products_equal_float64_bit_for_bit(seed, exponent, top, density, batch):
    rng = np.random.default_rng(seed)
    w = rng.integers(-top, top + 1, (37, 300)).astype(np.float64) * 2.0 ** exponent
    x = (rng.random((batch, 300)) < density).astype(np.float64)
    product = ExactProduct(w)
    assert product.units_t is not None                           # 300 x 32767 < 2**24: always taken here
    assert _bits_equal(product.of(x), x @ w.T)
    assert _bits_equal(product.of(3 * x), (3 * x) @ w.T)          # small integers, not only spikes


def test_the_largest_common_power_of_two_is_found_beyond_the_sample():
    """Every sampled entry is a multiple of 2**-3, one unsampled entry only of 2**-9: g is lowered to it."""
    w = np.full((64, 5000), 2.0 ** -3)
    w[7, 4999] = 2.0 ** -9
    units_t, g, bound = integer_units(w)
    assert g == 2.0 ** -9 and units_t.shape == (5000, 64) and units_t.dtype == np.float32
    assert np.array_equal(units_t.T.astype(np.float64) * g, w)
    assert bound == 5000 * 2 ** 6                                  # a full row of 2**-3 = 2**6 units


@pytest.mark.parametrize("make", [
    lambda rng: rng.normal(size=(20, 50)),                               # arbitrary floats
    lambda rng: np.full((2, 600), 2.0 ** 15 - 1),                        # odd integers: sums past 2**24
    lambda rng: np.where(rng.random((20, 50)) < 0.5, np.inf, 1.0),       # not finite
    lambda rng: np.full((20, 50), np.nan),
])
def test_no_float32_path_where_sums_could_round(make):
    w = make(np.random.default_rng(0))
    assert integer_units(w) is None
    product = ExactProduct(w)
    x = np.ones((2, w.shape[1]))
    with np.errstate(invalid="ignore"):
        out, expected = product.of(x), x @ w.T
    assert _bits_equal(out, expected) or np.isnan(w).any()


def test_inputs_that_are_not_small_integers_take_float64():
    w = np.random.default_rng(1).integers(-100, 101, (10, 40)).astype(np.float64)
    product = ExactProduct(w)
    assert product.units_t is not None
    for x in (np.full((1, 40), 0.5), np.full((1, 40), float(FLOAT32_EXACT)), np.full((1, 40), np.inf)):
        assert not product.exact_for(x)
        with np.errstate(invalid="ignore"):
            out, expected = product.of(x), x @ w.T
        assert _bits_equal(out, expected) or np.isinf(x).any()


def test_integer_weights_are_taken_as_they_are():
    w = (np.random.default_rng(2).integers(-127, 128, (30, 200)) * 64).astype(np.int16)
    units_t, g, bound = integer_units(w)
    assert g >= 64 and np.array_equal(units_t.T.astype(np.int64) * int(g), w.astype(np.int64))
