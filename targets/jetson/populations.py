"""The LIF populations of a Jetson plan's graph: their float spikes, and the one the ONNX model outputs
(what check and validation measure liveness on)."""

from __future__ import annotations

import numpy as np

from snncc.targets.jetson.plan import GraphPlan


def float_spikes(plan: GraphPlan, x: np.ndarray) -> dict[str, np.ndarray]:
    """Every LIF population's float spikes (B, T, n) on base-channel data (copies tiled as the authors do)."""
    from snncc.ir.simulate import simulate

    tiled = np.tile(x, (1, 1, plan.input_copies)) if plan.input_copies > 1 else x
    res = simulate(plan.graph, tiled.astype(np.float64), record="spikes")
    return {k: np.asarray(v).astype(np.uint8) for k, v in res.spikes.items()}


def output_population(plan: GraphPlan) -> str:
    """The LIF population whose spikes the Output carries (through any Readout)."""
    from snncc.ir.nodes import LIF

    node = plan.output_name
    while not isinstance(plan.graph.node(node), LIF):
        node = plan.graph.predecessors(node)[0]
    return node
