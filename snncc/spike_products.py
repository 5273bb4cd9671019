"""Products of spike inputs by a large matrix over the nonzero inputs only, in C (``spike_products.c``, built by the
system's C compiler on first use and cached: ``snncc.native``):

    out[b, j] = sum over i ascending with x[b, i] != 0 of  x[b, i] * m[i, j]          x: integers 0..255

A simulation step multiplies a few samples' spikes by the whole weight matrix; BLAS then reads (and packs) all of
it for a handful of rows, while this reads a row only for an input that spiked and skips silent ones. Integer
weights in 8 or 16 bits sum exactly in int32 (a quarter of float32's memory for 8-bit ones); float weights sum in
double in ascending input order, each term exact: the order of a sequential sum, the order this machine's OpenBLAS
takes too (the same bits, measured), and a BLAS that blocks its sums differently may differ in the last bit.

    available()                   whether the kernels are built here (else BLAS runs every product)
    counts(x)                     x as uint8 where it holds integers 0..255, else None
    worth_it(kind, size, batch, active, n_in)      whether the kernel beats BLAS for this product
    integer_sums(c, m_t)          (batch, n_out) int32 for int8 / int16 m_t, or None without a compiler
    float_sums(c, m_t)            (batch, n_out) float64 for float32 / float64 m_t, or None without a compiler
    FloatProduct(w)               x @ w.T by the kernel where it is faster, else BLAS (the IR reference's products)
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("spike_products.c")
# When the kernel beats BLAS (bench/speed/bench_spike_products.py, one thread): on matrices from about 600 x 600
# (integer units; float32 BLAS reads smaller ones from cache faster) or 450 x 450 (float weights), and while the
# batch's nonzero inputs per matrix row stay few (at 3,600 x 3,600: integer batch 4 at 40 % density in 0.23x BLAS's
# time, batch 16 at 40 % 0.8x, batch 64 at 40 % 1.5x; float batch 4 at 40 % 0.56x, batch 16 at 40 % 1.2x;
# at 900 x 900 batch 12 at 40 % both about 1.0x).
INTEGER_MIN_SIZE = 1 << 19   # entries (smaller: BLAS, nothing to build or load)
FLOAT_MIN_SIZE = 1 << 18
INTEGER_MAX_ACTIVE = 6       # nonzero inputs per matrix row, averaged over the batch, above which BLAS is faster
FLOAT_MAX_ACTIVE = 4
MAX_BATCH = 256              # spike_products.c's MAX_BATCH
_FUNCTIONS = {np.dtype(np.int8): "snncc_spike_product_i8", np.dtype(np.int16): "snncc_spike_product_i16",
              np.dtype(np.float32): "snncc_spike_product_f32", np.dtype(np.float64): "snncc_spike_product_f64"}


def _library():
    """The kernels with their argument types set (built and cached on first use), or None without a compiler."""
    from snncc.native import library

    lib = library(SOURCE, {}, "spike-products")
    if lib is not None and not getattr(lib, "snncc_typed", False):
        for name in _FUNCTIONS.values():
            fn = getattr(lib, name)
            fn.argtypes = [ctypes.c_void_p, ctypes.c_int64, ctypes.c_int64, ctypes.c_void_p, ctypes.c_int64,
                           ctypes.c_void_p]
            fn.restype = ctypes.c_int64
        lib.snncc_typed = True
    return lib


def available() -> bool:
    """Whether the kernels are built here (a C compiler found, the cache writable); else every product uses BLAS."""
    return _library() is not None


def counts(x: np.ndarray) -> np.ndarray | None:
    """x as C-contiguous uint8 where every entry is an integer 0..255, else None."""
    c = x.astype(np.uint8)
    return np.ascontiguousarray(c) if np.array_equal(c, x) else None


def worth_it(kind: str, size: int, batch: int, active: int, n_in: int) -> bool:
    """Whether the ``kind`` ("integer" or "float") kernel is taken for a ``size``-entry matrix with ``n_in`` rows
    and ``batch`` rows of x holding ``active`` nonzero entries (the thresholds above), and is built here (asked
    last: a product that would not take it builds nothing, and without a compiler no copy is made for it)."""
    min_size, per_row = ((INTEGER_MIN_SIZE, INTEGER_MAX_ACTIVE) if kind == "integer"
                         else (FLOAT_MIN_SIZE, FLOAT_MAX_ACTIVE))
    return size >= min_size and 0 < batch <= MAX_BATCH and active <= per_row * n_in and available()


def _run(c: np.ndarray, m_t: np.ndarray, out_type) -> np.ndarray | None:
    lib = _library()
    if lib is None:
        return None
    m_t = np.ascontiguousarray(m_t)
    out = np.empty((c.shape[0], m_t.shape[1]), out_type)
    fn = getattr(lib, _FUNCTIONS[m_t.dtype])
    if fn(c.ctypes.data, c.shape[0], c.shape[1], m_t.ctypes.data, m_t.shape[1], out.ctypes.data) != 0:
        return None
    return out


def integer_sums(c: np.ndarray, m_t: np.ndarray) -> np.ndarray | None:
    """c @ m_t in int32 for (batch, n_in) uint8 ``c`` and an (n_in, n_out) int8 / int16 ``m_t`` (the caller keeps
    max(c) * max_j sum_i |m_t[i, j]| below 2**24); None without the kernel."""
    return _run(c, m_t, np.int32)


def float_sums(c: np.ndarray, m_t: np.ndarray) -> np.ndarray | None:
    """c @ m_t in float64, summed in ascending input order, for (batch, n_in) uint8 ``c`` and an (n_in, n_out)
    float32 / float64 ``m_t`` (float64 only with c of 0 and 1); None without the kernel."""
    if m_t.dtype == np.float64 and c.size and c.max() > 1:
        raise ValueError("float64 weights take inputs of 0 and 1 only (larger products may round)")
    return _run(c, m_t, np.float64)


class FloatProduct:
    """x @ w.T for an (n_out, n_in) float64 matrix ``w``: ``float_sums`` for spike inputs where that is the faster
    product (ascending-order sums, the kernel reading ``w`` transposed, in float32 where every entry is a float32),
    else BLAS's ``x @ w.T`` (always for a matrix with a non-finite entry, where 0 * inf must give BLAS's NaN)."""

    _UNMADE = object()

    def __init__(self, w: np.ndarray):
        self.w = w
        self._w_t = self._UNMADE

    def transposed(self) -> np.ndarray | None:
        """w.T in C order, float32 where that holds every entry exactly, else float64; None for a non-finite
        ``w`` (made on first use)."""
        if self._w_t is self._UNMADE:
            from snncc.transpose import transposed

            w = self.w
            if not np.isfinite(w).all():
                self._w_t = None
            else:
                exact32 = np.array_equal(w.astype(np.float32), w)
                self._w_t = transposed(w, 1.0, np.float32 if exact32 else np.float64)
        return self._w_t

    def of(self, x: np.ndarray) -> np.ndarray:
        """(..., n_out) float64."""
        flat = x.reshape(-1, x.shape[-1])
        if worth_it("float", self.w.size, flat.shape[0], int(np.count_nonzero(flat)), self.w.shape[1]):
            c = counts(flat)
            w_t = None if c is None else self.transposed()
            if w_t is not None and (w_t.dtype == np.float32 or c.max(initial=0) <= 1):
                out = float_sums(c, w_t)
                if out is not None:
                    return out.reshape(tuple(x.shape[:-1]) + (self.w.shape[0],))
        return x @ self.w.T
