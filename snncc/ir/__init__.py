"""snncc's compiler IR: nodes, graph, validation, serialisation and the reference simulator.

The names are resolved on first use, so ``import snncc.ir.graph`` (or a CLI that only parses
options) does not pay for torch, which the reference simulator needs.
"""

from __future__ import annotations

import importlib

_HOMES = {
    "Graph": "graph",
    **{name: "nodes" for name in ("Node", "Input", "Dense", "LIF", "LSTM", "Readout", "Output")},
    "load_graph": "serialize", "save_graph": "serialize",
    "simulate": "simulate", "SimulationResult": "simulate",
    "validate": "validate",
}

__all__ = [
    "Graph", "Node", "Input", "Dense", "LIF", "LSTM", "Readout", "Output",
    "validate", "simulate", "SimulationResult", "save_graph", "load_graph",
]


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'snncc.ir' has no attribute {name!r}")
    return getattr(importlib.import_module(f"snncc.ir.{home}"), name)
