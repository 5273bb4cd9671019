"""A C source compiled once by the system's C compiler into a cached shared library (the one implementation is
``snncc.native``; see its docstring): a kernel that starts without numba's import and cache load.

    library(source, defines, name)   the loaded library (ctypes), built on first use; None without a compiler
    choice(variable)                 "auto" / "c" / "numba" from an environment variable
    settings()                       the environment that decides compiler and cache (a key for memos)
"""

from __future__ import annotations

from snncc.native import CHOICES, cache_dir, choice, compiler, library, settings

__all__ = ["library", "choice", "compiler", "cache_dir", "settings", "CHOICES"]
