"""numba kernels for the partitioner: one pass over a projection's synapses (O(nnz), no sort); ``kernels.py``
runs ``kernels.c`` instead wherever the system's C compiler builds it (the same integers, no numba start-up).

Synapses are read in CSC order (by source, destinations ascending). When every layer slice sits on
a core with a larger id than the slice before it (``cores_dst`` non-decreasing), a source's
synapses onto one core are consecutive, so each run is one (core, source) pair: one input axon on
the core, one synapse list (bits from a lookup table by range size and count) and one output axon
on the source's core.
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit.compute import sigint_deferred

with sigint_deferred():   # numba's C init would turn a Ctrl-C into an ImportError (snncc/interrupts.py)
    import numba


@numba.njit(cache=True, nogil=True)
def pair_usage(cptr, cidx, cores_dst, m_core, table, src_core, n_cores):
    """(input axons, synapse bits, output axons) per core; src_core[j] < 0: source j is off-chip."""
    axons = np.zeros(n_cores, np.int64)
    bits = np.zeros(n_cores, np.int64)
    out = np.zeros(n_cores, np.int64)
    n_pre = cptr.size - 1
    for j in range(n_pre):
        prev = -1
        cnt = 0
        for e in range(cptr[j], cptr[j + 1]):
            c = cores_dst[cidx[e]]
            if c != prev:
                if prev >= 0:
                    axons[prev] += 1
                    bits[prev] += table[m_core[prev], cnt]
                    if src_core[j] >= 0:
                        out[src_core[j]] += 1
                prev = c
                cnt = 0
            cnt += 1
        if prev >= 0:
            axons[prev] += 1
            bits[prev] += table[m_core[prev], cnt]
            if src_core[j] >= 0:
                out[src_core[j]] += 1
    return axons, bits, out


@numba.njit(cache=True, nogil=True)
def distinct_per_source(cptr, cidx, slice_of):
    """For each source: how many distinct destination slices its synapses reach (slice_of ascending)."""
    n_pre = cptr.size - 1
    out = np.zeros(n_pre, np.int64)
    for j in range(n_pre):
        prev = -1
        for e in range(cptr[j], cptr[j + 1]):
            c = slice_of[cidx[e]]
            if c != prev:
                out[j] += 1
                prev = c
    return out


@numba.njit(cache=True, nogil=True)
def transpose_indices(indptr, indices, n_cols):
    """CSC (cptr, cidx) of a CSR pattern; rows ascend within each column."""
    nnz = indices.size
    cptr = np.zeros(n_cols + 1, np.int64)
    for e in range(nnz):
        cptr[indices[e] + 1] += 1
    for j in range(n_cols):
        cptr[j + 1] += cptr[j]
    fill = cptr[:-1].copy()
    cidx = np.empty(nnz, np.int32)
    n_rows = indptr.size - 1
    for r in range(n_rows):
        for e in range(indptr[r], indptr[r + 1]):
            j = indices[e]
            cidx[fill[j]] = r
            fill[j] += 1
    return cptr, cidx
