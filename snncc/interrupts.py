"""Ctrl-C held back where a library would turn it into something else.

numba's C extensions import their helpers while ``import numba`` runs; a KeyboardInterrupt there is
printed as a traceback (``PyErr_Print``) and replaced by ``ImportError: numba._devicearray failed to
import``, which no caller can tell from a broken install. ``sigint_deferred`` records a SIGINT that
arrives during such a step instead of raising it, and raises it again, through whatever handler was
there before, as soon as the step is over (the CLI then says "interrupted" and exits 130).

A handler, not a signal mask: a process-directed signal goes to any thread that does not block it,
while Python runs its handlers in the main thread whichever thread received it.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def sigint_deferred() -> Iterator[None]:
    """SIGINT recorded while the body runs, raised again after it (main thread only: elsewhere a no-op)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda signum, _frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        signal.raise_signal(signal.SIGINT)      # as if it came now: KeyboardInterrupt under Python's handler
