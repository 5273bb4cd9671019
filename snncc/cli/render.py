"""Notes a frontend left on a graph, printed for the user (the records render themselves)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from snncc.cli.output import err_console

if TYPE_CHECKING:
    from snncc.ir.graph import Graph


def print_import_notes(graph: Graph) -> None:
    """What a frontend assumed (dt inferred, reset chosen, ...): one ``snncc: note:`` line each, on stderr."""
    source = graph.metadata.get("source_file", "")
    for note in graph.metadata.get("import_notes") or []:
        err_console.print(f"snncc: note: {source + ': ' if source else ''}{note}", markup=False, soft_wrap=True)
