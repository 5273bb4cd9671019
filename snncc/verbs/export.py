"""``snncc export`` as a function: a model written as a NIR graph for other frameworks."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.exporters.nir import ExportReport

FORMATS = ("nir",)


@dataclass
class ExportResult:
    """``format``: the format written; ``report``: the ``ExportReport`` (output, dt, export_dt, nodes,
    delay_nodes, convention, not_honoured); ``notes``: what the frontend assumed in loading."""

    format: str
    report: ExportReport
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        """What ``snncc export --json`` prints: the format and the report's fields."""
        from dataclasses import asdict

        from snncc.records import to_jsonable

        return to_jsonable({"format": self.format, **asdict(self.report)})

    def render_text(self, console: Console) -> None:
        for line in self.report.lines():
            console.print(line, markup=False)


def export(model: str | os.PathLike, *, output: str | os.PathLike, to: str = "nir",
           params: str | os.PathLike | None = None, dt: float | None = None, reset: str | None = None,
           nir_dt: float | None = None) -> ExportResult:
    """Write ``model`` as ``to`` (nir) into ``output`` atomically; ``nir_dt``: the step the NIR time
    constants are written for (default: the model's dt)."""
    from pathlib import Path

    from snncc.errors import SnnccError

    if to not in FORMATS:
        raise SnnccError(f"unknown export format {to!r}; choose one of {', '.join(FORMATS)}", field="--to")
    from snncc.exporters.nir import export_nir
    from snncc.frontends import LoadOptions, import_notes, load_model

    graph = load_model(Path(model), LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    report = export_nir(graph, Path(output), step=nir_dt)
    return ExportResult(to, report, import_notes(graph))
