"""Spikes times a large matrix over the nonzero inputs only (``snncc.spike_products``, C): integer sums equal the
exact product, float sums equal a sum in ascending input order bit for bit, and the products built on them
(``exact_products.UnitsProduct``, ``spike_products.FloatProduct``, the IR reference) give what BLAS gives."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snncc import spike_products
from snncc.exact_products import ExactProduct, UnitsProduct, integer_units
from snncc.spike_products import FloatProduct, counts, float_sums, integer_sums
from snncc_test_helpers import need_c_compiler


@pytest.fixture(autouse=True)
def _kernel_from_small_sizes(monkeypatch):
    """The kernels take matrices from 64 K entries in these tests (their own thresholds are larger: kept small
    here so that every test runs in milliseconds)."""
    monkeypatch.setattr(spike_products, "INTEGER_MIN_SIZE", 1 << 16)
    monkeypatch.setattr(spike_products, "FLOAT_MIN_SIZE", 1 << 16)


def _ascending(c: np.ndarray, m_t: np.ndarray) -> np.ndarray:
    """The float kernel's rule written out: for each sample, the rows of its nonzero inputs added one after another
    in ascending input order, in float64."""
    out = np.zeros((c.shape[0], m_t.shape[1]))
    for b in range(c.shape[0]):
        for i in np.flatnonzero(c[b]):
            out[b] += float(c[b, i]) * m_t[i].astype(np.float64)
    return out


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 31), batch=st.integers(1, 9), n_in=st.integers(1, 70), n_out=st.integers(1, 90),
       density=st.floats(0.0, 1.0), narrow=st.sampled_from([np.int8, np.int16]), top=st.sampled_from([1, 3, 255]))
def test_integer_sums_are_the_exact_product(seed, batch, n_in, n_out, density, narrow, top):
    need_c_compiler()
    rng = np.random.default_rng(seed)
    info = np.iinfo(narrow)
    m_t = rng.integers(info.min, info.max + 1, (n_in, n_out)).astype(narrow)
    c = np.where(rng.random((batch, n_in)) < density, rng.integers(1, top + 1, (batch, n_in)), 0).astype(np.uint8)
    out = integer_sums(c, m_t)
    assert out.dtype == np.int32
    np.testing.assert_array_equal(out, c.astype(np.int64) @ m_t.astype(np.int64))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 31), batch=st.integers(1, 9), n_in=st.integers(1, 70), n_out=st.integers(1, 90),
       density=st.floats(0.0, 1.0), kind=st.sampled_from([np.float32, np.float64]))
def test_float_sums_add_inputs_in_ascending_order_bit_for_bit(seed, batch, n_in, n_out, density, kind):
    need_c_compiler()
    rng = np.random.default_rng(seed)
    m_t = (rng.normal(size=(n_in, n_out)) * 10.0 ** rng.integers(-3, 4, (n_in, 1))).astype(kind)
    top = 1 if kind == np.float64 else 255      # double weights only with 0/1 inputs (larger products may round)
    c = np.where(rng.random((batch, n_in)) < density, rng.integers(1, top + 1, (batch, n_in)), 0).astype(np.uint8)
    out = float_sums(c, m_t)
    assert out.dtype == np.float64 and out.tobytes() == _ascending(c, m_t).tobytes()


def test_double_weights_refuse_inputs_above_one():
    with pytest.raises(ValueError, match="0 and 1"):
        float_sums(np.full((1, 4), 2, np.uint8), np.ones((4, 3)))


def test_only_integers_0_to_255_count_as_spike_counts():
    assert counts(np.array([[0.0, 1.0, 255.0]])).dtype == np.uint8
    for bad in ([[0.5, 1.0]], [[256.0, 0.0]], [[-1.0, 0.0]], [[np.nan, 0.0]]):
        with np.errstate(invalid="ignore"):
            assert counts(np.array(bad)) is None


def _chip_like(rng, n_out: int, n_in: int) -> np.ndarray:
    return rng.integers(-127, 128, (n_out, n_in)).astype(np.float64) * 2.0 ** -6


@pytest.mark.parametrize("batch,density", [(1, 0.05), (4, 0.4), (12, 0.1), (40, 0.9)])
def test_units_products_equal_the_float64_product_with_and_without_the_kernel(batch, density, monkeypatch):
    """Exact either way: the kernel where it is taken (small batches, sparse spikes), BLAS where not, and with no
    compiler at all; the same bits as float64 BLAS every time."""
    need_c_compiler()
    rng = np.random.default_rng(batch)
    w = _chip_like(rng, 300, 260)                                   # 78,000 entries: above 64 K
    x = (rng.random((batch, 260)) < density).astype(np.float64)
    product = ExactProduct(w)
    with_kernel = product.of(x)
    assert with_kernel.tobytes() == (x @ w.T).tobytes()
    monkeypatch.setattr(spike_products, "_library", lambda: None)
    assert ExactProduct(w).of(x).tobytes() == with_kernel.tobytes()


def test_the_kernel_is_taken_where_it_is_worth_it(monkeypatch):
    need_c_compiler()
    rng = np.random.default_rng(3)
    units_t, _, bound = integer_units(_chip_like(rng, 300, 260))
    calls = []
    real = spike_products.integer_sums
    monkeypatch.setattr(spike_products, "integer_sums", lambda c, m: calls.append(c.shape) or real(c, m))
    product = UnitsProduct(units_t, bound)
    product.of((rng.random((4, 260)) < 0.3).astype(np.float64))          # 4 samples, 30 %: the kernel
    product.of(np.ones((64, 260)))                                        # every input of 64 samples: BLAS
    product.of((rng.random((12, 260)) < 0.6).astype(np.float64))         # 7.2 active per row: BLAS
    product.of(np.full((2, 260), 0.5) * 2)                                # 1.0 everywhere, 2 samples: the kernel
    UnitsProduct(units_t[:10, :10].copy(), bound).of(np.ones((1, 10)))    # a small matrix: BLAS, nothing built
    assert calls == [(4, 260), (2, 260)]
    assert product.narrow().dtype == np.int8


def test_sixteen_bit_units_and_units_beyond_sixteen_bits():
    need_c_compiler()
    rng = np.random.default_rng(4)
    x = (rng.random((3, 300)) < 0.3).astype(np.float64)
    for top, kind in ((2000, np.int16), (40000, None)):
        w = rng.integers(-top, top + 1, (260, 300)).astype(np.float64)
        product = ExactProduct(w)
        assert product.units is not None
        assert product.of(x).tobytes() == (x @ w.T).tobytes()
        narrow = product.units.narrow()
        assert (narrow is None) if kind is None else narrow.dtype == kind


def test_float_product_takes_the_kernel_for_spikes_and_blas_otherwise(monkeypatch):
    need_c_compiler()
    rng = np.random.default_rng(5)
    w = rng.normal(size=(300, 260)).astype(np.float32).astype(np.float64)     # float32 values: a float32 copy
    product = FloatProduct(w)
    spikes = (rng.random((4, 260)) < 0.4).astype(np.float64)
    taken = product.of(spikes)
    assert product.transposed().dtype == np.float32
    assert taken.tobytes() == _ascending(spikes.astype(np.uint8), w.T).tobytes()
    np.testing.assert_allclose(taken, spikes @ w.T, rtol=1e-12, atol=1e-12)   # BLAS may order its sums otherwise
    graded = np.full((2, 260), 0.5)
    assert product.of(graded).tobytes() == (graded @ w.T).tobytes()           # not spike counts: BLAS
    dense = np.ones((64, 260))
    assert product.of(dense).tobytes() == (dense @ w.T).tobytes()             # 64 active per row: BLAS
    w64 = w + 1e-12                                                           # no longer float32: kept in float64
    assert FloatProduct(w64).of(spikes).tobytes() == _ascending(spikes.astype(np.uint8), w64.T).tobytes()
    assert FloatProduct(w64).of(2 * spikes).tobytes() == ((2 * spikes) @ w64.T).tobytes()   # counts: BLAS


def test_without_a_compiler_no_copy_is_made_for_the_kernel(monkeypatch):
    """Where the kernels do not build, products go straight to BLAS: no int8 or transposed copy of the matrix."""
    monkeypatch.setattr(spike_products, "_library", lambda: None)
    rng = np.random.default_rng(8)
    x = (rng.random((4, 260)) < 0.3).astype(np.float64)
    exact = ExactProduct(_chip_like(rng, 300, 260))
    floats = FloatProduct(rng.normal(size=(300, 260)))
    assert exact.of(x).tobytes() == (x @ exact.w.T).tobytes()
    assert floats.of(x).tobytes() == (x @ floats.w.T).tobytes()
    from snncc import exact_products

    assert floats._w_t is FloatProduct._UNMADE and exact.units._narrow is exact_products._UNSET


def test_a_non_finite_weight_leaves_the_product_to_blas():
    w = np.ones((300, 260))
    w[5, 7] = np.inf
    x = np.zeros((2, 260))
    x[0, 1] = 1.0
    with np.errstate(invalid="ignore"):
        out, expected = FloatProduct(w).of(x), x @ w.T
    assert np.isnan(out[:, 5]).all() and np.array_equal(np.isnan(out), np.isnan(expected))


def _rsnn(integer: bool):
    from snncc.ir import LIF, Dense, Graph, Input, Output, validate

    rng = np.random.default_rng(7)
    scale = (lambda a: np.round(a * 128) / 128) if integer else (lambda a: a)
    g = Graph(0.001)
    g.add("x", Input(20))
    g.add("w", Dense(scale(rng.normal(0.0, 0.6, (300, 20)))))
    g.add("n", LIF(300, 0.005, 0.02, 1.0, reset="subtract"))
    g.add("r", Dense(scale(rng.normal(0.0, 0.12, (300, 300)))))
    g.add("o", Output(300))
    for a, b in (("x", "w"), ("w", "n"), ("r", "n"), ("n", "o")):
        g.connect(a, b)
    g.connect("n", "r", delay=1)
    validate(g)
    return g


def test_the_ir_reference_of_a_large_recurrent_network_with_and_without_the_kernels(monkeypatch):
    """A 300-neuron recurrent network (90,000 recurrent weights, float and integer-valued): the IR reference's
    spikes with the kernels equal those without them, and every record to the last bit for integer weights."""
    need_c_compiler()
    import importlib

    from snncc.ir.simulate import simulate

    sim = importlib.import_module("snncc.ir.simulate")
    x = (np.random.default_rng(6).random((3, 40, 20)) < 0.3).astype(np.float64)
    for integer, kind in ((False, FloatProduct), (True, ExactProduct)):
        g = _rsnn(integer)
        assert isinstance(sim._Runner(g, np.dtype(np.float64), "all").p["r"][0], kind)
        kernel = simulate(g, x, record="all")
        with monkeypatch.context() as m:
            m.setattr(spike_products, "_library", lambda: None)
            blas = simulate(g, x, record="all")
        assert kernel.spikes["n"].any() and not kernel.spikes["n"].all()
        for name in blas.spikes:
            assert np.array_equal(kernel.spikes[name], blas.spikes[name])
        for name in blas.voltage:
            if integer:
                assert kernel.voltage[name].tobytes() == blas.voltage[name].tobytes()
            else:
                np.testing.assert_allclose(kernel.voltage[name], blas.voltage[name], rtol=1e-9, atol=1e-12)
