"""The verbs every target offers, as a small protocol."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from snncc.ir.graph import Graph


class Artefact(Protocol):
    """A lowered model: something that can be written, checked and summarised."""

    def write(self, path: str | Path) -> None:
        """Write atomically (no partial output on failure), byte-identical for identical input."""

    def summary(self) -> dict[str, Any]:
        """Plain-data record of what was built (printed as text or JSON)."""


class Target(Protocol):
    name: str
    description: str
    output_kind: str  # "file" or "directory"

    def lower(self, graph: Graph, options: dict[str, Any]) -> Artefact:
        """Lower a validated IR graph; raise SnnccError if the target cannot express it."""
