"""Which implementation runs Loihi's compiled kernels (the emulator's and the partitioner's): C sources built once
by the system's C compiler (``kit.native``: no numba start-up), or numba where no compiler builds them.

``$SNNCC_LOIHI_KERNEL``: "auto" (default: C where it builds, else numba), "c" (C, or a one-line error), "numba".
Both give the same integers (tests/loihi/emulation/test_ckernel.py, tests/loihi/mapping/test_ckernels.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

from snncc.targets.kit import SnnccError
from snncc.targets.kit.native import choice, library, settings

VARIABLE = "SNNCC_LOIHI_KERNEL"
_prepared: dict[tuple, Any] = {}    # (choice, source, defines, settings) -> prepare(library), or None (numba)


def c_library(source: Path, defines: dict[str, str], name: str, prepare: Callable[[Any], Any] = lambda lib: lib):
    """``prepare(library)`` of ``source`` built (cached) and loaded, once per process and settings; None where numba
    is to run. Choice "c" without a build: an error."""
    how = choice(VARIABLE)
    if how == "numba":
        return None
    key = (how, source, tuple(sorted(defines.items())), *settings())
    if key not in _prepared:
        lib = library(source, defines, name)
        if lib is None and how == "c":
            raise SnnccError("the C kernel could not be built (no C compiler found, or it failed); set it to 'numba' "
                             "or 'auto'", field=VARIABLE)
        _prepared[key] = None if lib is None else prepare(lib)
    return _prepared[key]
