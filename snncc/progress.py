"""The one progress convention of snncc's verbs, shared by every layer that reports work done.

``Progress``: ``progress(done, total, phase)``, called as work gets done: ``done`` never falls while
``phase`` (a short text such as ``"checking"`` or ``"epoch 2/3"``) stays the same, and ``done <=
total``. ``counting`` turns it into the ``progress(n)`` (n more samples done) that a target's
sample loops call.
"""

from __future__ import annotations

from typing import Callable

Progress = Callable[[int, int, str], None]
StepProgress = Callable[[int], None]


def counting(progress: Progress | None, total: int, phase: str) -> StepProgress | None:
    """A ``progress(n)`` (n more done) that reports ``progress(done, total, phase)``."""
    if progress is None:
        return None
    done = [0]

    def advanced(n: int) -> None:
        done[0] += n
        progress(done[0], total, phase)

    return advanced
