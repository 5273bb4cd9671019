"""Printing reports: rich text for people, JSON for tools (same record, two renderings).

On a terminal, text wraps and tables fit its width. Anywhere else (a pipe, a file) output is meant
to be read by programs: no line is wrapped and no table cell is cut or wrapped (``WholeLines``).
"""

from __future__ import annotations

import contextlib
import json
from typing import Any

from rich.console import Console, ConsoleDimensions

UNBOUNDED_WIDTH = 1_000_000   # columns offered when not a terminal: wider than any line snncc prints


class WholeLines(Console):
    """A rich console that fits a terminal, and elsewhere offers ``UNBOUNDED_WIDTH`` columns: text is
    never wrapped and tables are as wide as their cells (rich otherwise assumes 80 columns, or the
    width of whichever standard stream is a terminal). Whether its stream is a terminal is asked at
    each print, so a stream replaced later (a test's capture) is honoured."""

    def _on_terminal(self) -> bool:
        try:
            return bool(self.file.isatty())
        except (AttributeError, ValueError, OSError):
            return False

    @property
    def size(self) -> ConsoleDimensions:
        real = super().size
        return real if self._on_terminal() else ConsoleDimensions(UNBOUNDED_WIDTH, real.height)


console = WholeLines(highlight=False)
err_console = WholeLines(stderr=True, highlight=False)


def print_json(record: Any) -> None:
    from snncc.records import to_jsonable   # numpy-aware; imported only when JSON is printed

    print(json.dumps(to_jsonable(record), indent=2, sort_keys=False))


def print_record(record: Any, json_out: bool) -> None:
    """A verb's record: ``as_dict()`` as JSON, or ``render_text`` for people."""
    if json_out:
        print_json(record.as_dict())
    else:
        record.render_text(console)


def bar_columns(remaining: bool = False) -> tuple:
    """The data and training bars' columns: phase, bar, done/total, elapsed (and time remaining)."""
    from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    return columns + ((TimeRemainingColumn(),) if remaining else ())


LINE_EVERY_S = 10.0      # outside a terminal: a progress line per phase and at most this often within one


def _on_terminal() -> bool:
    try:
        return bool(err_console.file.isatty())
    except (AttributeError, ValueError, OSError):
        return False


@contextlib.contextmanager
def progress_bar(*columns, disable: bool = False, transient: bool = True):
    """Yields ``progress(done, total, phase)`` for a verb. On a terminal: a bar on stderr (removed at the end when
    ``transient``), started at the first report that leaves work to do (a run finished in one report shows none).
    Anywhere else (a pipe, a log): one line on stderr when a phase starts and at most every ``LINE_EVERY_S``
    seconds within it, ``snncc: progress: <phase>: <done>/<total>``, so long steps never look hung."""
    import time

    state: dict[str, Any] = {}

    def report(done: int, total: int, phase: str = "") -> None:
        if disable:
            return
        if not _on_terminal():
            now = time.monotonic()
            if phase != state.get("phase") or now - state.get("said", 0.0) >= LINE_EVERY_S:
                if done < total:       # a phase already complete says nothing new
                    print(f"snncc: progress: {phase or 'working'}: {done}/{total}", file=err_console.file, flush=True)
                state["phase"], state["said"] = phase, now
            return
        if "bar" not in state:
            if done >= total:
                return
            from rich.progress import Progress

            state["bar"] = Progress(*columns, console=err_console, transient=transient)
            state["bar"].start()
            state["task"] = state["bar"].add_task(phase, total=total)
        state["bar"].update(state["task"], completed=done, total=total, description=phase)

    try:
        yield report
    finally:
        if "bar" in state:
            state["bar"].stop()
