"""The library functions behind the CLI's target verbs, one small module per verb (faced by ``snncc.api``).

Each takes the CLI's file argument first and its options as keyword arguments, asks the
registered target for the capability it needs (``snncc.targets.capability``) and returns a record
with ``as_dict()`` (what ``--json`` prints) and ``render_text(console)`` (what the command prints).

``progress``, where a verb takes it, is runtime state, never an option: a callable
``progress(done, total, phase)`` called with the samples (or protocol steps) done so far.
"""

from __future__ import annotations

from snncc.progress import Progress, counting

VerbProgress = Progress      # progress(done, total, phase) (``snncc.progress``)

__all__ = ["VerbProgress", "counting"]
