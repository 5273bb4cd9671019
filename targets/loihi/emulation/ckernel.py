"""The emulator's kernel compiled from C (``kernel.c``): the numba kernel's rules and program, no numba start-up.

``$SNNCC_LOIHI_KERNEL`` chooses (``targets/loihi/native.py``): "auto" (default: the C kernel where the system's C
compiler builds it, else the numba kernel), "c" (the C kernel or an error), "numba". Both give the same integers
(``tests/loihi/emulation`` runs every program shape through both and the numpy statement); a run's summary names
the one that ran.
A build per type signature (accumulator, weight, state) is cached (``kit.native``); a warm call loads it in
about a millisecond, where the numba kernel's import and cache load take about 0.4 s.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.loihi.chip import DECAY_SHIFT
from snncc.targets.loihi.native import VARIABLE, c_library

SOURCE = Path(__file__).with_name("kernel.c")
C_KERNEL, NUMBA_KERNEL = "C kernel", "numba kernel"
_C_TYPES = {"int8": "int8_t", "int16": "int16_t", "int32": "int32_t", "int64": "int64_t"}

_P, _I = ctypes.c_void_p, ctypes.c_int64
_BUILDS: dict[tuple, tuple] = {}     # (acc, weight, state) -> (the build's -D defines, its cache name)


class Program(ctypes.Structure):
    """``program_t`` of kernel.c, field for field (its size is checked against the compiled one)."""

    _fields_ = [("x", _P), ("steps", _I), ("width", _I),
                ("n", _P), ("noff", _P), ("kl", _P), ("groups", _P), ("lay", _P), ("layers", _I), ("n_groups", _I),
                ("wflat", _P), ("dflat", _P),
                ("woff", _P), ("roff", _P), ("duni", _P), ("druni", _P), ("sptr", _P), ("spost", _P),
                ("wsp", _P), ("rsp", _P),
                ("keep_u", _P), ("keep_v", _P), ("vth", _P), ("bias", _P), ("p32", _P),
                ("ring", _I), ("record_all", _I),
                ("out_spikes", _P), ("n_out", _I),
                ("all_s", _P), ("all_u", _P), ("all_v", _P), ("units", _I),
                ("ovf", _P), ("wraps", _P)]


def compiled(acc: np.dtype, weight: np.dtype, state: np.dtype):
    """The C kernel's ``run_chunk`` for these types, or None where the numba kernel is to run (choice "numba",
    or "auto" without a working compiler). Choice "c" without a build is an error."""
    if (acc, weight, state) not in _BUILDS:
        names = [np.dtype(t).name for t in (acc, weight, state)]
        _BUILDS[acc, weight, state] = ({"ACC_T": _C_TYPES[names[0]], "W_T": _C_TYPES[names[1]],
                                        "STATE_T": _C_TYPES[names[2]], "DECAY_SHIFT": str(DECAY_SHIFT)},
                                       "loihi-kernel-" + "-".join(names))
    defines, name = _BUILDS[acc, weight, state]
    return c_library(SOURCE, defines, name, prepare=_run_chunk_of)


def _run_chunk_of(lib):
    """The library's run_chunk, typed, once its program layout is checked against ``Program``."""
    lib.snncc_loihi_program_size.restype = ctypes.c_int64
    if lib.snncc_loihi_program_size() != ctypes.sizeof(Program):
        raise SnnccError("the compiled kernel's program layout differs from ckernel.Program", field=VARIABLE)
    run = lib.snncc_loihi_run_chunk
    run.argtypes = [ctypes.POINTER(Program), ctypes.c_int64, ctypes.c_int64]
    run.restype = ctypes.c_int
    return run


def _pointers(typed: dict) -> tuple[dict[str, int], list]:
    """Each array's address, checked C-contiguous and of the type kernel.c reads; and the arrays (keep them alive)."""
    pointers, keep = {}, []
    for field_name, (a, dtype) in typed.items():
        if a.dtype != dtype or not a.flags.c_contiguous:
            raise SnnccError(f"the kernel's array {field_name} must be C-contiguous {np.dtype(dtype).name}",
                             field=field_name)
        keep.append(a)
        pointers[field_name] = a.__array_interface__["data"][0]
    return pointers, keep


def network_part(flat, registers: tuple) -> tuple[dict, list]:
    """The fields of a ``Program`` that describe the network: ``flat`` (``flat.Flat``) and its ``registers`` for the
    run (the same for every run of a flattened network: ``flat.run_flat`` keeps them); and the arrays they point
    into."""
    prog = flat.prog
    lay, wraps, kl, groups, _ = registers
    pointers, keep = _pointers({
        "n": (prog.n, np.int64), "noff": (prog.noff, np.int64), "kl": (kl, np.int64), "groups": (groups, np.int64),
        "lay": (lay, np.int64), "wflat": (flat.wflat, flat.wflat.dtype), "dflat": (flat.dflat, np.int64),
        "woff": (flat.woff, np.int64), "roff": (flat.roff, np.int64), "duni": (flat.duni, np.int64),
        "druni": (flat.druni, np.int64), "sptr": (flat.sptr, np.int64), "spost": (flat.spost, np.int32),
        "wsp": (flat.wsp, np.int64), "rsp": (flat.rsp, np.int64), "keep_u": (flat.keep_u, np.int64),
        "keep_v": (flat.keep_v, np.int64), "vth": (flat.vth, np.int64), "bias": (flat.bias, np.int64),
        "p32": (flat.p32, np.int32), "wraps": (wraps, np.int64)})
    return {**pointers, "layers": prog.n.shape[0], "n_groups": groups.shape[0], "ring": int(prog.ring)}, keep


def program(network: dict, x, record_all, out, all_s, all_u, all_v, ovf) -> tuple[Program, list]:
    """The ``Program`` of a run: ``network`` (``network_part``) and this run's inputs and outputs; and the arrays
    it points into (keep them alive while the kernel runs)."""
    pointers, keep = _pointers({"x": (x, np.uint8), "out_spikes": (out, np.uint8), "all_s": (all_s, np.uint8),
                                "all_u": (all_u, np.int32), "all_v": (all_v, np.int32), "ovf": (ovf, np.int64)})
    batch, steps, width = x.shape
    prog = Program(steps=steps, width=width, record_all=int(record_all), n_out=out.shape[2],
                   units=all_s.shape[2] if record_all else 0, **network, **pointers)
    return prog, keep


def run_chunk(run, prog: Program, lo: int, hi: int) -> None:
    """Samples lo..hi-1 (ctypes releases the GIL for the call, so chunks run on threads side by side)."""
    if run(ctypes.byref(prog), lo, hi) != 0:
        raise MemoryError("the C kernel could not allocate its state")
