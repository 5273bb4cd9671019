"""The ``ir`` target: the validated IR graph itself, written as a ``.snnir`` file.

Useful to inspect what a frontend understood and to hand a model between tools; ``snncc
compile out.snnir --target ...`` reads it back. This module is the registered entry point: it
imports its work (the graph's serialiser and summary) on use.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets.kit import SnnccError
from snncc.targets.kit import Progress as PhaseProgress
from snncc.targets.base import Given, TargetOptions, target_options

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.ir.graph import Graph
    from snncc.targets.base import Model


@dataclass(frozen=True)
class IROptions(TargetOptions):
    """The ``ir`` target takes no options."""


@dataclass
class IRArtefact:
    graph: Graph

    def write(self, path: str | Path) -> None:
        from snncc.ir.serialize import save_graph

        save_graph(self.graph, path)

    def summary(self) -> Mapping[str, object]:
        from snncc.ir.summary import graph_summary

        found: Mapping[str, object] = graph_summary(self.graph)
        return found

    def render_text(self, console: Console) -> None:
        from snncc.ir.summary_text import render_graph_summary

        render_graph_summary(dict(self.summary()), console)


class IRTarget:
    name = "ir"
    description = "snncc's IR as a .snnir file (validated graph, explicit dt, delays, reset)"
    output_kind = "file"
    output_suffix = ".snnir"
    options_type = IROptions

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> IRArtefact:
        from snncc.ir.graph import Graph

        target_options(self, options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("ir writes IR graphs only (model_kinds)", field="--target")
        return IRArtefact(model.copy())


target = IRTarget()
