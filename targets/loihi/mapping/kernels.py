"""The partitioner's kernels: ``kernels.c`` built by the system's C compiler (no numba start-up), else the numba
kernels of ``numba_kernels.py`` (``$SNNCC_LOIHI_KERNEL``, ``targets/loihi/native.py``). The same integers either way.

    transpose_indices(indptr, indices, n_cols)      CSC (cptr int64, cidx int32) of a CSR pattern
    distinct_per_source(cptr, cidx, slice_of)       distinct destination slices per source
    pair_usage(cptr, cidx, cores_dst, m_core, table, src_core, n_cores)   (axons, bits, out) per core
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from snncc.targets.loihi.native import VARIABLE, c_library

SOURCE = Path(__file__).with_name("kernels.c")
_P, _I = ctypes.c_void_p, ctypes.c_int64
_SIGNATURES = {"snncc_loihi_transpose_indices": [_P, _P, _I, _I, _P, _P, _P],
               "snncc_loihi_distinct_per_source": [_P, _P, _I, _P, _P],
               "snncc_loihi_pair_usage": [_P, _P, _I, _P, _P, _P, _I, _P, _P, _P, _P]}


def _typed(lib):
    """The library with its functions' argument types set."""
    for name, args in _SIGNATURES.items():
        getattr(lib, name).argtypes = args
        getattr(lib, name).restype = None
    return lib


def _c():
    """The loaded C library (argument types set), or None where the numba kernels run."""
    return c_library(SOURCE, {}, "loihi-mapping", prepare=_typed)


def _i64(a) -> np.ndarray:
    return np.ascontiguousarray(a, np.int64)


def _i32(a) -> np.ndarray:
    return np.ascontiguousarray(a, np.int32)


def _at(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


def transpose_indices(indptr, indices, n_cols: int) -> tuple[np.ndarray, np.ndarray]:
    """CSC (cptr, cidx) of a CSR pattern; rows ascend within each column."""
    lib = _c()
    if lib is None:
        from snncc.targets.loihi.mapping.numba_kernels import transpose_indices as numba_kernel

        return numba_kernel(indptr, indices, n_cols)
    indptr, indices = _i64(indptr), _i32(indices)
    cptr = np.zeros(int(n_cols) + 1, np.int64)
    cidx = np.empty(indices.size, np.int32)
    fill = np.empty(int(n_cols), np.int64)
    lib.snncc_loihi_transpose_indices(_at(indptr), _at(indices), indptr.size - 1, int(n_cols), _at(cptr), _at(cidx),
                                      _at(fill))
    return cptr, cidx


def distinct_per_source(cptr, cidx, slice_of) -> np.ndarray:
    """For each source: how many distinct destination slices its synapses reach (slice_of ascending)."""
    lib = _c()
    if lib is None:
        from snncc.targets.loihi.mapping.numba_kernels import distinct_per_source as numba_kernel

        return numba_kernel(cptr, cidx, slice_of)
    cptr, cidx, slice_of = _i64(cptr), _i32(cidx), _i64(slice_of)
    out = np.zeros(cptr.size - 1, np.int64)
    lib.snncc_loihi_distinct_per_source(_at(cptr), _at(cidx), cptr.size - 1, _at(slice_of), _at(out))
    return out


def pair_usage(cptr, cidx, cores_dst, m_core, table, src_core, n_cores: int):
    """(input axons, synapse bits, output axons) per core; src_core[j] < 0: source j is off-chip."""
    lib = _c()
    if lib is None:
        from snncc.targets.loihi.mapping.numba_kernels import pair_usage as numba_kernel

        return numba_kernel(cptr, cidx, cores_dst, m_core, table, src_core, n_cores)
    cptr, cidx, cores_dst, m_core, src_core = _i64(cptr), _i32(cidx), _i64(cores_dst), _i64(m_core), _i64(src_core)
    table = _i64(table)
    axons, bits, out = (np.zeros(int(n_cores), np.int64) for _ in range(3))
    lib.snncc_loihi_pair_usage(_at(cptr), _at(cidx), cptr.size - 1, _at(cores_dst), _at(m_core), _at(table),
                               table.shape[1], _at(src_core), _at(axons), _at(bits), _at(out))
    return axons, bits, out
