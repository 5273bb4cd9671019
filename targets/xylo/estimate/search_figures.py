"""What a search trial's model costs on Xylo (the ``hardware`` capability, for ``snncc hpo``).

Per trial the model is lowered like ``snncc compile --target xylo``. A model that breaks a design rule
of the chip is not an error here but a figure: ``feasible`` 0 with the rule's line, the neurons counted
from the graph. A feasible one gives the hidden and output neurons and synapses it uses, and the
real-time margin (dt over the worst-case step time from per-operation cycle costs: an ESTIMATE, not a
measurement), and, with ``emulate_samples`` > 0, the accuracy of the network spec in snncc's bit-exact emulator
on that many labelled samples. No energy figure: none is published for these networks.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from snncc.targets.base import Figure, Given, Objective
from snncc.targets.kit import SnnccError
from snncc.targets.kit.search import SearchCosts, tiled_inputs, timed

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

LABEL = ("Xylo: neurons and synapses used and design-rule feasibility (exact); real-time margin an ESTIMATE from "
         "per-operation cycle costs (not a measurement); no energy figure")

OBJECTIVES = {
    "neurons": Objective("hidden_neurons", "minimize", "hidden neurons"),
    "feasible": Objective("feasible", "maximize", "1 if the chip holds the model, else 0"),
    "real_time_margin": Objective("real_time_margin", "maximize", "dt / worst-case step time (ESTIMATE)"),
    "emulated_accuracy": Objective("emulated_accuracy", "maximize", "%"),
}

# what a search report shows per trial, in column order; the front weighs accuracy, neurons, margin, feasibility
COLUMNS = {
    "neurons": Figure("hidden_neurons", "hidden neurons"),
    "output_neurons": Figure("output_neurons", "output neurons"),
    "synapses": Figure("synapses", "synapses"),
    "feasible": Figure("feasible", "feasible (1/0)"),
    "real_time_margin": Figure("real_time_margin", "real-time margin (EST.)",
                               axis="real-time margin: dt / worst-case step time (ESTIMATE)"),
    "emulated_accuracy": Figure("emulated_accuracy", "emulated %"),                 # stored in %
}
FRONT = ("neurons", "real_time_margin", "feasible")


@dataclass
class XyloFigures:
    chip: str
    feasible: int                          # 1: lowered within every design rule of the chip; 0: refused
    hidden_neurons: int
    output_neurons: int
    synapses: int = 0
    real_time_margin: float = 0.0          # ESTIMATE; 0 when infeasible
    cycles_per_step_worst: float = 0.0     # ESTIMATE
    rule: str = ""
    refusal: str = ""                      # the design rule's line when infeasible
    emulated_accuracy: float | None = None
    emulated_on: int = 0
    seconds: float = 0.0
    label: str = LABEL
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def _graph_neurons(graph: Graph) -> tuple[int, int]:
    from snncc.ir.nodes import LIF

    sizes = [op.n for _, op in graph.items() if isinstance(op, LIF)]
    return (sum(sizes[:-1]), sizes[-1]) if sizes else (0, 0)


class XyloHardware(SearchCosts):
    """The ``hardware`` capability's answer: objectives and per-trial figures (nothing published to show)."""

    objectives = OBJECTIVES
    columns = COLUMNS
    front = FRONT
    label = LABEL

    def figures(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
                estimate_samples: int = 16, emulate_samples: int = 0) -> XyloFigures:
        """Lower ``graph`` for the chip of ``options``; ``emulate_samples`` > 0: the emulated accuracy on the
        first that many of ``inputs`` (B, T, C) and ``labels`` (``estimate_samples`` is unused: nothing is
        estimated from inputs)."""
        from snncc.targets.base import target_options
        from snncc.targets.xylo.chip import get_chip
        from snncc.targets.xylo.estimate.real_time import real_time
        from snncc.targets.xylo.lowering.lower import lower

        with timed() as clock:
            opts = target_options(self.target, options, "lower")
            chip = get_chip(opts.chip).key
            hidden, out = _graph_neurons(graph)
            try:
                low = lower(graph, opts)
            except SnnccError as err:
                figures = XyloFigures(chip, 0, hidden, out, refusal=err.line())
            else:
                spec = low.xylo_spec
                rt = real_time(spec, float(spec.dt))
                figures = XyloFigures(chip, 1, hidden, out, int(sum(np.count_nonzero(w) for w in (
                    spec.weights_in, spec.weights_rec, spec.weights_out))), float(rt.as_dict()["margin"]),
                    rt.cycles_worst, low.rule, notes=list(low.changes))
                if emulate_samples > 0:
                    m = min(int(emulate_samples), int(inputs.shape[0]))
                    x = tiled_inputs(np.asarray(inputs[:m]), graph, spec.n_in)
                    counts = low.read_output(_emulate(spec, low.chip_input(x.astype(np.uint8))),
                                             x.shape[1]).sum(axis=1)
                    figures.emulated_accuracy = float(100.0 * np.mean(np.argmax(counts, axis=1)
                                                                      == np.asarray(labels[:m])))
                    figures.emulated_on = m
        figures.seconds = clock.seconds
        return figures


def _emulate(spec, x: np.ndarray) -> np.ndarray:
    from snncc.targets.xylo.emulation.emulator import emulate

    return emulate(spec, x).output_spikes
