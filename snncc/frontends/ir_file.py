"""``.snnir`` files written by ``snncc compile --target ir`` (see ``snncc.ir.serialize``)."""

from __future__ import annotations

from pathlib import Path

from snncc.ir.graph import Graph
from snncc.ir.serialize import load_graph


def load(path: Path, options) -> Graph:
    return load_graph(path)
