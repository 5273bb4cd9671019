"""``.snnir`` files written by ``snncc compile --target ir`` (see ``snncc.ir.serialize``)."""

from __future__ import annotations

from pathlib import Path

from snncc.ir.graph import Graph
from snncc.ir.serialize import load_graph


def load(path: Path, options) -> Graph:
    from snncc.frontends.load_options import refuse_options

    refuse_options(options, (), "an snncc IR file, which states dt and every reset", path)
    return load_graph(path)
