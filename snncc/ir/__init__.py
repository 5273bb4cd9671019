"""snncc's compiler IR: nodes, graph, validation, serialisation and the reference simulator."""

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Conv, Dense, Input, Node, Output, Readout
from snncc.ir.serialize import load_graph, save_graph
from snncc.ir.simulate import SimulationResult, simulate
from snncc.ir.validate import validate

__all__ = [
    "Graph", "Node", "Input", "Dense", "Conv", "LIF", "LSTM", "Readout", "Output",
    "validate", "simulate", "SimulationResult", "save_graph", "load_graph",
]
