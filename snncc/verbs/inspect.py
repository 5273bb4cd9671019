"""``snncc inspect`` as a function: what a frontend understood of a model file, as an IR summary."""

from __future__ import annotations

from typing import TYPE_CHECKING

import os
from dataclasses import dataclass, field

if TYPE_CHECKING:
    from rich.console import Console


@dataclass
class InspectResult:
    """``summary``: ``snncc.ir.summary.graph_summary`` of the loaded graph (nodes, sizes, time
    constants, delays, reset, metadata); ``notes``: what the frontend assumed (``<file>: <note>``)."""

    summary: dict
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        """What ``snncc inspect --json`` prints: the summary."""
        from snncc.records import to_jsonable

        return to_jsonable(self.summary)

    def render_text(self, console: Console) -> None:
        from snncc.ir.summary_text import render_graph_summary

        render_graph_summary(self.summary, console)


def inspect(model: str | os.PathLike, *, params: str | os.PathLike | None = None, dt: float | None = None,
            reset: str | None = None) -> InspectResult:
    """Load ``model`` (.pt, .nir, .snnir; ``params`` for a SpyTorch weight list, ``dt``/``reset`` for
    formats without them), validate its IR and summarise it."""
    from pathlib import Path

    from snncc.frontends import LoadOptions, import_notes, load_model
    from snncc.ir.summary import graph_summary

    graph = load_model(Path(model), LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    return InspectResult(graph_summary(graph), import_notes(graph))
