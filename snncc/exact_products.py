"""Matrix products by integer-valued inputs that float32 computes exactly, so half the memory is read per product.

A weight matrix W whose entries are integers m times one power of two g (chip weights, quantized weights in
chip units) and an input x of small integers (spikes) give sums

    (x @ W.T)[b, j] = g * sum_i x[b, i] * m[j, i]

whose every partial sum, in any order, is an integer multiple of g below 2**24 * g whenever
max|x| * max_j sum_i |m[j, i]| < 2**24. Such sums are exact in float32 and in float64 alike, so the float32
product, widened and multiplied by g (a power of two: exact), equals the float64 product bit for bit.
``ExactProduct.of`` takes that path where the input allows it and the float64 product otherwise.

Spikes and spike counts (integers 0..255) by a large matrix whose units fit 8 or 16 bits go further: the C kernel
of ``snncc.spike_products`` adds the rows of the nonzero inputs in int32 (the same exact integers, a quarter of
float32's memory read for 8-bit units, no work for silent inputs). Without a compiler, float32 BLAS as above.
"""

from __future__ import annotations

import numpy as np

from snncc import spike_products

FLOAT32_EXACT = 1 << 24        # integers below this are exact in float32, and so is every sum that stays below it
SAMPLE = 4096                  # entries that rule a matrix of arbitrary floats out before it is scanned whole
BLOCK = 1 << 18                # entries converted at a time (no temporary as large as the matrix)


def _lowest_bit_exponent(values: np.ndarray) -> int:
    """The exponent of the smallest power of two dividing every nonzero float in ``values`` (finite, nonzero)."""
    mantissa, exponent = np.frexp(values)                      # |mantissa| in [0.5, 1): an integer times 2**-53
    digits = np.abs(np.ldexp(mantissa, 53)).astype(np.int64)   # exact: below 2**53
    low = digits & -digits                                     # the lowest set bit of each
    return int((exponent - 53 + np.frexp(low.astype(np.float64))[1] - 1).min())


def _units_in_float32(w: np.ndarray, g: float) -> tuple[np.ndarray, float, float] | None:
    """((w / g').T as C-contiguous float32, g', the largest row sum of |w / g'|) for g' the largest power of two at
    most ``g`` dividing every entry, when that sum is below 2**24; else None. In blocks of rows (no temporary as
    large as ``w``); entries ``g`` does not divide lower g' and the blocks are converted again once. (Held
    transposed: ``x @ units_t`` is the faster float32 product for a few rows of x.)"""
    rows = max(1, BLOCK // max(1, w.shape[1]))
    blocks = range(0, w.shape[0], rows)
    for _ in range(2):
        units_t = np.empty(w.shape[::-1], np.float32)
        bound, lower = 0.0, g
        for start in blocks:
            part = w[start:start + rows]
            m = part / g                                   # exact: g is a power of two
            fraction = m != np.trunc(m)
            if fraction.any():
                lower = min(lower, 2.0 ** _lowest_bit_exponent(part[fraction].astype(np.float64)))
                continue
            bound = max(bound, float(np.abs(m).sum(axis=1).max()))
            if not bound < FLOAT32_EXACT:
                return None
            if lower == g:
                units_t[:, start:start + rows] = m.T
        if lower == g:
            return units_t, g, bound
        g = lower
    return None


def integer_units(w: np.ndarray) -> tuple[np.ndarray, float, float] | None:
    """(m.T, g, bound) with w = m * g (w float or integer), m integer-valued (m.T C-contiguous float32), g a power of
    two and bound the largest row sum of |m|, below 2**24; None otherwise (fractional or huge spreads: arbitrary
    float weights).

    g is first the largest power of two dividing a sample of the entries (at least the whole's, so a sampled entry
    past the bound rules the matrix out: arbitrary floats cost no scan), lowered where an entry needs it (a smaller
    g only raises the sums)."""
    w = np.asarray(w)
    if w.ndim != 2 or not w.size or w.dtype.kind not in "fiu":
        return None
    flat = w.reshape(-1)
    sample = flat[:: max(1, flat.size // SAMPLE)].astype(np.float64)
    if not np.isfinite(sample).all():
        return None
    sample = sample[sample != 0]
    g = 2.0 ** _lowest_bit_exponent(sample) if sample.size else 1.0
    if sample.size and float(np.abs(sample).max()) / g >= FLOAT32_EXACT:
        return None
    if not np.isfinite(w).all():
        return None
    return _units_in_float32(w, g)


_UNSET = object()


class UnitsProduct:
    """x @ units_t for an integer-valued float32 matrix ``units_t`` (n_in, n_out) and integer-valued x whose every
    partial sum stays below 2**24 (the caller's rule: max|x| * bound < 2**24); float64 of the exact integer sums.

    Inputs 0..255 go to the C kernel (``spike_products.integer_sums``) where the matrix is large, its units fit 16
    bits and x is sparse enough; else x with at most ``sparse_max_density`` of its entries nonzero is taken as a
    scipy sparse matrix (0: never); else float32 BLAS. Every path gives the same integers (exact sums, any order)."""

    def __init__(self, units_t: np.ndarray, bound: float, sparse_max_density: float = 0.0):
        self.units_t, self.bound, self.sparse_max_density = units_t, float(bound), float(sparse_max_density)
        self._narrow = _UNSET

    def narrow(self) -> np.ndarray | None:
        """units_t in int8 or int16 where its entries fit (made on first use), else None."""
        if self._narrow is _UNSET:
            u = self.units_t         # max |u| from its extremes: no temporary as large as the matrix
            top = max(abs(float(u.max())), abs(float(u.min()))) if u.size else 0.0
            kind = np.int8 if top <= 127 else np.int16 if top <= 32767 else None
            self._narrow = None if kind is None else self.units_t.astype(kind)
        return self._narrow

    def _by_kernel(self, x: np.ndarray, active: int) -> np.ndarray | None:
        n_in = self.units_t.shape[0]
        if x.ndim != 2 or not spike_products.worth_it("integer", self.units_t.size, x.shape[0], active, n_in):
            return None
        c = spike_products.counts(x)
        narrow = None if c is None else self.narrow()
        out = None if narrow is None else spike_products.integer_sums(c, narrow)
        return None if out is None else out.astype(np.float64)

    def of(self, x: np.ndarray) -> np.ndarray:
        """(..., n_out) float64: the exact integer sums x @ units_t."""
        units_t = self.units_t
        flat = x.reshape(-1, x.shape[-1]) if x.ndim != 2 else x
        active = int(np.count_nonzero(flat))
        if active == 0:
            return np.zeros(tuple(x.shape[:-1]) + (units_t.shape[1],))
        out = self._by_kernel(flat, active)
        if out is None and active <= self.sparse_max_density * flat.size:
            import scipy.sparse as sp

            out = np.asarray((sp.csr_matrix(flat.astype(np.float32)) @ units_t)).astype(np.float64)
        if out is None:
            out = (flat.astype(np.float32) @ units_t).astype(np.float64)
        return out.reshape(tuple(x.shape[:-1]) + (units_t.shape[1],))


class ExactProduct:
    """x @ w.T for (..., n_in) inputs and an (n_out, n_in) float64 weight matrix, in float32 where exact (module
    docstring: small integer inputs, weights integer multiples of a power of two), else in float64; the two give
    the same bits."""

    def __init__(self, w: np.ndarray):
        self.w = np.asarray(w, np.float64)
        found = integer_units(self.w)
        self.units_t, self.scale, self.bound = found if found is not None else (None, 1.0, 0.0)
        self.units = None if found is None else UnitsProduct(self.units_t, self.bound)

    def exact_for(self, x: np.ndarray) -> bool:
        """Whether float32 sums ``x @ units_t`` exactly: x integer-valued and max|x| * bound below 2**24."""
        if self.units_t is None or not x.size:
            return False
        top = float(np.abs(x).max())
        return top * self.bound < FLOAT32_EXACT and bool((x == np.trunc(x)).all())

    def of(self, x: np.ndarray) -> np.ndarray:
        """(..., n_out) float64, equal bit for bit to ``x @ w.T`` in float64."""
        if self.exact_for(x):
            out = self.units.of(x)
            return out * self.scale if self.scale != 1.0 else out
        return x @ self.w.T
