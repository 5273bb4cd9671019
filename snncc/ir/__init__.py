"""snncc's compiler IR: nodes, graph, validation, serialisation and the reference simulator.

The reference simulator runs in torch. ``simulate`` and ``SimulationResult`` are imported on first
use, so that reading, validating or printing a graph does not import torch (start-up time of
``inspect``, ``map``, ``report``, ``emulate``).
"""

import sys
import types

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Conv, Dense, Input, Node, Output, Readout
from snncc.ir.serialize import load_graph, save_graph
from snncc.ir.validate import validate

__all__ = [
    "Graph", "Node", "Input", "Dense", "Conv", "LIF", "LSTM", "Readout", "Output",
    "validate", "simulate", "SimulationResult", "save_graph", "load_graph",
]

_SIMULATOR_NAMES = ("simulate", "SimulationResult")


def __getattr__(name: str):
    """``snncc.ir.simulate`` (the function) and ``snncc.ir.SimulationResult``, imported when first asked."""
    if name in _SIMULATOR_NAMES:
        from snncc.ir.simulate import SimulationResult, simulate

        globals().update(simulate=simulate, SimulationResult=SimulationResult)
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class _Package(types.ModuleType):
    """Keeps the name ``simulate`` for the function: importing the submodule ``snncc.ir.simulate``
    (which Python records as an attribute of this package) must not replace it."""

    def __setattr__(self, name: str, value) -> None:
        if name == "simulate" and isinstance(value, types.ModuleType):
            return              # the submodule stays in sys.modules["snncc.ir.simulate"]
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
