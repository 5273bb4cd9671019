"""Notes a frontend left on a graph, printed for the user (the records render themselves)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from snncc.cli.output import err_console

if TYPE_CHECKING:
    from snncc.ir.graph import Graph


def print_notes(notes: list[str]) -> None:
    """One ``snncc: note: <line>`` per note, on stderr (control characters escaped: one line each)."""
    from snncc.errors import one_line

    for note in notes:
        err_console.print(f"snncc: note: {one_line(note)}", markup=False, soft_wrap=True)


def print_warnings(warnings: list[str]) -> None:
    """One ``snncc: warning: <line>`` per warning, on stderr."""
    for warning in warnings:
        err_console.print(f"snncc: warning: {warning}", markup=False, soft_wrap=True)


def print_import_notes(graph: Graph) -> None:
    """What a frontend assumed (dt inferred, reset chosen, ...): one ``snncc: note:`` line each, on stderr."""
    from snncc.frontends import import_notes

    print_notes(import_notes(graph))
