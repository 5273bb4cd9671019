"""Bounds checked before any work is allocated: sizes, time axes and weight value types.

Every check raises one ``SnnccError`` that states the bound it applied:

* memory: an array snncc is about to build may take at most ``memory_cap()`` bytes -- half of
  this machine's physical memory (``os.sysconf``), or ``SNNCC_MAX_MEMORY`` bytes if that
  environment variable is set. Sizes from a file (an architecture record, a bundle's declared
  dataset shapes) are multiplied out with Python integers, so a size of 10**7 neurons is refused
  before torch or numpy is asked for 400 TB.
* time: a sample has at most ``MAX_TIME_STEPS`` steps (a documented cap: one million steps is
  1000 s at dt = 1 ms; the Braille recordings are 270 steps). An emulated stream of samples and
  gaps has at most ``MAX_STREAM_STEPS``.
* counts (neurons, channels, copies, samples, steps) are whole numbers >= 1.
* weights are real numbers: complex values (whose imaginary part a cast would silently drop) and
  text or byte strings (which numpy would parse as numbers) are refused.
"""

from __future__ import annotations

import math
import os
from typing import Any

from snncc.errors import SnnccError

MAX_TIME_STEPS = 1_000_000
MAX_STREAM_STEPS = 100_000_000
MEMORY_ENV = "SNNCC_MAX_MEMORY"
_FALLBACK_MEMORY = 8 * 2**30   # when the OS does not say (non-POSIX)


def physical_memory() -> int:
    """Bytes of physical memory of this machine (8 GiB if the OS does not tell)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return _FALLBACK_MEMORY


def memory_cap() -> int:
    """The most bytes one array (or one model's weights) may take: SNNCC_MAX_MEMORY, else half the RAM."""
    env = os.environ.get(MEMORY_ENV, "").strip()
    if env:
        try:
            value = int(float(env))
        except ValueError:
            raise SnnccError(f"must be a number of bytes, got {env!r}", field=MEMORY_ENV) from None
        if value > 0:
            return value
    return physical_memory() // 2


def describe_cap() -> str:
    if os.environ.get(MEMORY_ENV, "").strip():
        return f"{human_bytes(memory_cap())} (set by {MEMORY_ENV})"
    return (f"{human_bytes(memory_cap())}: half of this machine's {human_bytes(physical_memory())} of memory; "
            f"set {MEMORY_ENV} to change")


def human_bytes(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if abs(n) < 1024 or unit == "EiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.3g} {unit}"
        n /= 1024
    raise AssertionError("unreachable")  # pragma: no cover


def check_memory(n_bytes: int, what: str, *, file: str | None = None, field: str | None = None) -> None:
    """Refuse building ``what`` if it needs more than ``memory_cap()`` bytes."""
    if n_bytes > memory_cap():
        raise SnnccError(f"{what} would need {human_bytes(n_bytes)}, more than snncc allows one array on this "
                         f"machine ({describe_cap()})", file=file, field=field)


def whole_number(value: Any, *, file: str | None = None, field: str | None = None, minimum: int = 1,
                 maximum: int | None = None, what: str = "") -> int:
    """``value`` as an int in [minimum, maximum]; booleans, fractions, NaN and text are refused."""
    ok = isinstance(value, int) and not isinstance(value, bool)
    if not ok and isinstance(value, float) and math.isfinite(value) and value == int(value):
        value, ok = int(value), True
    if not ok:
        raise SnnccError(f"must be a whole number >= {minimum}{' (' + what + ')' if what else ''}, got {value!r}",
                         file=file, field=field)
    if value < minimum:
        raise SnnccError(f"must be >= {minimum}, got {value}", file=file, field=field)
    if maximum is not None and value > maximum:
        raise SnnccError(f"must be <= {maximum}, got {value}", file=file, field=field)
    return int(value)


def positive_number(value: Any, *, file: str | None = None, field: str | None = None) -> float:
    """A finite float > 0 (booleans and text refused)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise SnnccError(f"must be a positive finite number, got {value!r}", file=file, field=field)
    return float(value)


def check_time_steps(steps: float, what: str, *, file: str | None = None, field: str | None = None,
                     cap: int = MAX_TIME_STEPS) -> None:
    """A time axis of ``steps`` steps: >= 1 and at most ``cap`` (MAX_TIME_STEPS, documented above)."""
    if not (steps >= 1):
        raise SnnccError(f"{what} gives {steps:g} time steps; at least 1 is needed", file=file, field=field)
    if steps > cap:
        raise SnnccError(f"{what} gives {steps:.4g} time steps, more than snncc's cap of {cap:,} "
                         "(snncc.limits.MAX_TIME_STEPS)", file=file, field=field)


def real_dtype_problem(dtype: Any) -> str | None:
    """Why values of ``dtype`` (numpy or torch) are not real numbers, or None if they are."""
    name = str(dtype)
    if "complex" in name:
        return f"complex values ({name}); weights must be real numbers (a cast would drop the imaginary part)"
    if name.startswith("torch."):   # complex was caught above; float, int and bool tensors are real
        return None
    import numpy as np

    kind = np.dtype(dtype).kind
    if kind in "biuf":
        return None
    if kind in "SUa":
        return f"text ({name}), not numbers; weights must be stored as real numbers, never parsed from strings"
    return f"values of type {name}; weights must be real numbers"


def check_real(values: Any, *, file: str | None = None, field: str | None = None) -> None:
    """Refuse complex, string and object arrays (numpy arrays, torch tensors or nested lists)."""
    dtype = getattr(values, "dtype", None)
    if dtype is None:
        import numpy as np

        if isinstance(values, (str, bytes)):
            problem = real_dtype_problem(np.asarray(values).dtype)
        else:
            try:
                problem = real_dtype_problem(np.asarray(values).dtype)
            except (ValueError, TypeError):
                problem = "a ragged or non-numeric structure; weights must be a real numeric array"
    else:
        problem = real_dtype_problem(dtype)
    if problem:
        raise SnnccError(problem, file=file, field=field)
