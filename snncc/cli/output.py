"""Printing reports: rich text for people, JSON for tools (same record, two renderings)."""

from __future__ import annotations

import contextlib
import json
from typing import Any

from rich.console import Console

console = Console(highlight=False)
err_console = Console(stderr=True, highlight=False)


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


@contextlib.contextmanager
def progress_bar(*columns, disable: bool = False, transient: bool = True):
    """Yields ``progress(done, total, phase)`` for a verb: a bar on stderr (removed at the end when
    ``transient``), started at the first report that leaves work to do (a run finished in one report
    shows none)."""
    state: dict[str, Any] = {}

    def report(done: int, total: int, phase: str = "") -> None:
        if disable:
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
