"""The ``ir`` target: the validated IR graph itself, written as a ``.snnir`` file.

Useful to inspect what a frontend understood and to hand a model between tools; ``snncc
compile out.snnir --target ...`` reads it back.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from snncc.ir.graph import Graph
from snncc.ir.serialize import save_graph
from snncc.ir.summary import graph_summary
from snncc.targets.base import IROptions, TargetOptions, target_options


@dataclass
class IRArtefact:
    graph: Graph

    def write(self, path: str | Path) -> None:
        save_graph(self.graph, path)

    def summary(self) -> dict[str, Any]:
        return graph_summary(self.graph)

    def render_text(self, console) -> None:
        from snncc.ir.summary_text import render_graph_summary

        render_graph_summary(self.summary(), console)


class IRTarget:
    name = "ir"
    description = "snncc's IR as a .snnir file (validated graph, explicit dt, delays, reset)"
    output_kind = "file"
    output_suffix = ".snnir"
    options_type = IROptions

    def lower(self, graph: Graph, options: TargetOptions | dict[str, Any] | None = None, *, progress=None) -> IRArtefact:
        target_options(self, options)
        return IRArtefact(graph.copy())


target = IRTarget()
