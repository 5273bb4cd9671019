"""What a search trial's model costs on Loihi 1 (the ``hardware`` capability, for ``snncc hpo``).

Per trial: lowered like ``snncc compile --target loihi`` (timing, quantization, register values,
core map -- checked against the IR reference), then emulated on held-out samples for the synaptic
ops, energy (uJ) and delay (ms) per sample from Davies et al. 2018 Table 2 costs -- an ESTIMATE, not
a measurement -- and, optionally, ``snncc check``'s bit-exact emulated accuracy on a subset.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from snncc.targets.base import Figure, Given, Objective
from snncc.targets.kit.search import SearchCosts, tiled_inputs, timed

if TYPE_CHECKING:
    from snncc.ir.graph import Graph
    from snncc.targets.loihi.capabilities import LoihiTarget

ESTIMATE_LABEL = "ESTIMATE (not a measurement): Loihi 1 dynamic energy and delay, Davies 2018 Table 2 costs"

# what a search may optimise beside accuracy: name -> key of HardwareFigures.as_dict()
OBJECTIVES = {
    "emulated_accuracy": Objective("emulated_accuracy", "maximize", "%"),
    "energy": Objective("energy_uj_per_sample", "minimize", "uJ/sample (ESTIMATE)"),
    "cores": Objective("cores", "minimize", "cores"),
    "synops": Objective("synaptic_ops_per_sample", "minimize", "synaptic ops/sample"),
    "delay": Objective("delay_ms_per_sample", "minimize", "ms/sample (ESTIMATE)"),
}

# what a search report shows per trial, in column order; the front weighs accuracy, energy and cores
COLUMNS = {
    "cores": Figure("cores", "cores", axis="Loihi cores"),
    "synops": Figure("synaptic_ops_per_sample", "synops/sample"),
    "energy": Figure("energy_uj_per_sample", "energy uJ (EST.)", axis="energy per sample, uJ (ESTIMATE)", log=True,
                     field="energy_uj"),
    "delay": Figure("delay_ms_per_sample", "delay ms (EST.)", field="delay_ms"),
    "emulated_accuracy": Figure("emulated_accuracy", "emulated %", scale=100.0),    # stored as a fraction
}
FRONT = ("energy", "cores")


@dataclass
class HardwareFigures:
    cores: int
    chips: int
    synaptic_ops_per_sample: float
    spikes_per_sample: float
    energy_uj_per_sample: float          # ESTIMATE
    delay_ms_per_sample: float           # ESTIMATE
    t_sample: int
    estimated_on: int                    # samples emulated for the estimate
    emulated_accuracy: float | None = None        # bit-exact emulator, on ``emulated_on`` samples
    float_accuracy_same_samples: float | None = None
    emulated_on: int = 0
    seconds: float = 0.0
    label: str = ESTIMATE_LABEL
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def fit_inputs(x: np.ndarray, network) -> np.ndarray:
    """(B, T, C) events -> the network's input width (input copies tiled) and tSample steps (pad / cut)."""
    x = np.asarray(x, dtype=np.uint8)
    width = network.input_width
    if x.shape[2] != width:
        x = np.tile(x, (1, 1, width // x.shape[2]))
    t = network.t_sample
    if x.shape[1] < t:
        x = np.concatenate([x, np.zeros((x.shape[0], t - x.shape[1], x.shape[2]), x.dtype)], axis=1)
    return x[:, :t]


def _published() -> dict[str, float | str]:
    from snncc.targets.loihi.estimate.energy import PAPER_RSNN

    return {"energy": PAPER_RSNN["energy_uj_per_sample"], "cores": PAPER_RSNN["cores"],
            "delay": PAPER_RSNN["delay_ms_per_sample"], "accuracy": PAPER_RSNN["accuracy_loihi_percent"],
            "label": "paper: measured on Loihi (real data, th 1)"}


class LoihiHardware(SearchCosts):
    """The ``hardware`` capability's answer (``kit.search.SearchCosts``): objectives, the paper's measurement,
    and per-trial figures."""

    objectives = OBJECTIVES
    columns = COLUMNS
    front = FRONT
    label = ESTIMATE_LABEL

    def __init__(self, target: LoihiTarget) -> None:
        super().__init__(target, _published())

    def figures(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
                estimate_samples: int = 16, emulate_samples: int = 0) -> HardwareFigures:
        """Lower ``graph`` for Loihi; estimate on the first ``estimate_samples`` of ``inputs`` (B, T, C).

        The caller orders ``inputs`` (the trial objective shuffles its held-out samples with the plan's
        seed). ``emulate_samples`` > 0: also the bit-exact emulated accuracy (and the float model's) on
        the first that many samples, through ``snncc check``'s runs."""
        from snncc.targets.loihi.estimate.energy import emulate_and_estimate
        from snncc.targets.loihi.mapping.coremap import CoreMap

        with timed() as clock:
            artefact = self.target.lower(graph, options)
            network = artefact.network
            core_map = CoreMap.from_dict(network.core_map)
            n = max(1, min(int(estimate_samples), int(inputs.shape[0])))
            x = fit_inputs(inputs[:n], network)
            est = emulate_and_estimate(network, core_map, x, f"{n} held-out samples")
            figures = HardwareFigures(
                cores=int(core_map.n_cores), chips=int(core_map.n_chips),
                synaptic_ops_per_sample=float(est.counts["synaptic_ops"]),
                spikes_per_sample=float(est.counts["spikes"]), energy_uj_per_sample=float(est.energy_uj["total"]),
                delay_ms_per_sample=float(est.delay_ms), t_sample=int(network.t_sample), estimated_on=n,
                notes=[f"scale rule {artefact.quantization.get('rule')}", *artefact.notes])
            if emulate_samples > 0:
                m = min(int(emulate_samples), int(inputs.shape[0]))
                xe = tiled_inputs(inputs[:m], graph, network.input_width)
                record = self.target.check(graph, np.asarray(xe, np.uint8), np.asarray(labels[:m]), options)
                assert record.accuracy is not None
                figures.emulated_accuracy = float(record.accuracy["artefact"])
                figures.float_accuracy_same_samples = float(record.accuracy["float"])
                figures.emulated_on = m
        figures.seconds = clock.seconds
        return figures
