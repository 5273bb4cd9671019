"""A C source compiled once by the system's C compiler into a cached shared library (the one implementation is
``snncc.native``; see its docstring): a kernel that starts without numba's import and cache load.

    library(source, defines, name)   the loaded library (ctypes), built on first use; None without a compiler
    choice(variable)                 "auto" / "c" / "numba" from an environment variable
"""

from __future__ import annotations

from snncc.native import CHOICES, cache_dir, choice, compiler, library

__all__ = ["library", "choice", "compiler", "cache_dir", "CHOICES"]
