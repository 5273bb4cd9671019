"""A C source compiled once by the system's C compiler into a cached shared library, loaded with ctypes.

A kernel compiled this way starts in a millisecond where a numba kernel needs its import and cache load
(about 0.4 s); a target keeps its numba kernel for machines without a compiler (``library`` returns None).

    library(source, defines, name)   the loaded library, compiled on first use; None without a compiler
    choice(variable)                 "auto" / "c" / "numba" from an environment variable (default "auto")
    settings()                       the environment that decides compiler and cache (a key for memos)

The cache (``$SNNCC_CACHE_DIR``, else ``$XDG_CACHE_HOME/snncc``, else ``~/.cache/snncc``) holds one file per
source, defines, flags and CPU (the build uses ``-march=native``, so a home directory shared by different
machines gets one build each). A build goes to a temporary name and is renamed into place, so concurrent
first uses never load a half-written file. The compiler is ``$SNNCC_CC``, else ``$CC``, else ``cc`` or ``gcc``.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import stat
import subprocess
import sys
import threading
from pathlib import Path

from snncc.errors import SnnccError

CHOICES = ("auto", "c", "numba")
FLAGS = ("-O3", "-std=c99", "-fwrapv", "-fPIC", "-shared")
NATIVE = ("-march=native",)       # tried first; dropped where the compiler refuses it
BUILD_TIMEOUT_S = 300

_loaded: dict[Path, ctypes.CDLL | None] = {}       # by file
_requested: dict[tuple, ctypes.CDLL | None] = {}   # by (source, defines, name, the settings below)
_ENVIRONMENT = ("SNNCC_CC", "CC", "PATH", "SNNCC_CACHE_DIR", "XDG_CACHE_HOME", "HOME")   # what finds compiler and cache
_UNSEEN = object()
_lock = threading.Lock()


def choice(variable: str) -> str:
    """The implementation a user asked for in ``variable``: "auto" (C where a compiler builds it), "c", "numba"."""
    value = os.environ.get(variable, "auto").strip().lower() or "auto"
    if value not in CHOICES:
        raise SnnccError(f"must be one of {', '.join(CHOICES)} (got {value!r})", field=variable)
    return value


def settings() -> tuple:
    """The environment that decides which compiler builds and where the cache is (a key for memos)."""
    return tuple(os.environ.get(k) for k in _ENVIRONMENT)


def compiler() -> str | None:
    """The C compiler to build with: $SNNCC_CC, $CC, cc or gcc on the PATH; None if there is none."""
    for name in (os.environ.get("SNNCC_CC"), os.environ.get("CC"), "cc", "gcc"):
        if name:
            found = shutil.which(name)
            if found:
                return found
    return None


def cache_dir() -> Path:
    if os.environ.get("SNNCC_CACHE_DIR"):
        return Path(os.environ["SNNCC_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "snncc"


def _cpu() -> str:
    """What -march=native depends on: the CPU's model and feature flags (Linux), else the platform's names."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            lines = [ln for ln in f.read(65536).splitlines() if ln.startswith(("model name", "flags", "Features"))]
        return "|".join(dict.fromkeys(lines))
    except OSError:
        return f"{platform.machine()}|{platform.processor()}"


def library(source: Path, defines: dict[str, str], name: str) -> ctypes.CDLL | None:
    """``source`` built with ``defines`` (-D NAME=VALUE) and loaded; compiled on first use and cached.

    None when no compiler is found or the build fails (the caller falls back to its numba kernel)."""
    request = (source, tuple(sorted(defines.items())), name, *settings())
    found = _requested.get(request, _UNSEEN)
    if found is not _UNSEEN:                  # looked up before, with the same settings: no file system access
        return found
    cc = compiler()
    if cc is None:
        _requested[request] = None
        return None
    with _lock:
        if request not in _requested:     # the source hashed and the cache looked up once per process
            key = hashlib.sha256(b"\0".join([source.read_bytes(), repr(request[1]).encode(), " ".join(FLAGS).encode(),
                                             _cpu().encode(), cc.encode(), sys.platform.encode()])).hexdigest()[:20]
            path = cache_dir() / f"{name}-{key}.so"
            if path not in _loaded:
                found = _load(path) if path.exists() else None     # a file that does not load is built again
                _loaded[path] = found if found is not None else _build(cc, source, defines, path)
            _requested[request] = _loaded[path]
        return _requested[request]


def _load(path: Path) -> ctypes.CDLL | None:
    """The library at ``path``, if it loads and is this user's own file that no one else may write (code is loaded
    only from there: a cache directory shared with others must not hand this process their code)."""
    try:
        info = path.stat()
        owner = os.geteuid() if hasattr(os, "geteuid") else info.st_uid      # (no user ids to compare off POSIX)
        if info.st_uid != owner or info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            return None
        return ctypes.CDLL(str(path))
    except OSError:
        return None


def _build(cc: str, source: Path, defines: dict[str, str], path: Path) -> ctypes.CDLL | None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(path.parent, os.W_OK):     # a read-only cache: no build (the numba kernel runs instead)
        return None
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    args = [f"-D{k}={v}" for k, v in defines.items()]
    try:
        for extra in (NATIVE, ()):
            try:
                done = subprocess.run([cc, *FLAGS, *extra, *args, "-o", str(tmp), str(source)],
                                      capture_output=True, timeout=BUILD_TIMEOUT_S)
            except (OSError, subprocess.TimeoutExpired):
                return None
            if done.returncode == 0:
                try:
                    os.chmod(tmp, 0o755)        # nobody else may write it (``_load``), whatever the umask
                    os.replace(tmp, path)
                except OSError:                 # e.g. another user's file in a shared directory
                    return None
                return _load(path)
        return None
    finally:
        if tmp.exists():
            tmp.unlink()
