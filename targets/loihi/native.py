"""Which implementation runs Loihi's compiled kernels (the emulator's and the partitioner's): C sources built once
by the system's C compiler (``kit.native``: no numba start-up), or numba where no compiler builds them.

``$SNNCC_LOIHI_KERNEL``: "auto" (default: C where it builds, else numba), "c" (C, or a one-line error), "numba".
Both give the same integers (tests/loihi/emulation/test_ckernel.py, tests/loihi/mapping/test_ckernels.py).
"""

from __future__ import annotations

from pathlib import Path

from snncc.targets.kit import SnnccError
from snncc.targets.kit.native import choice, library

VARIABLE = "SNNCC_LOIHI_KERNEL"


def c_library(source: Path, defines: dict[str, str], name: str):
    """``source`` built (cached) and loaded, or None where numba is to run; choice "c" without a build: an error."""
    how = choice(VARIABLE)
    if how == "numba":
        return None
    lib = library(source, defines, name)
    if lib is None and how == "c":
        raise SnnccError("the C kernel could not be built (no C compiler found, or it failed); set it to 'numba' or "
                         "'auto'", field=VARIABLE)
    return lib
