"""What a search trial's model costs as C on a microcontroller (the ``hardware`` capability, for ``snncc hpo``).

Per trial the model is lowered like ``snncc compile --target c`` (the rule and part of ``options``). Figures:
flash (constant data of snn.c, exact) and RAM (sizeof(snn_state_t), exact) and whether both fit the part;
synaptic operations per step (each event's fan-out row, counted in the emulator on the first
``estimate_samples`` inputs: the event-driven work, which instructions per step follow, without a QEMU run per
trial); with ``emulate_samples`` > 0, the emulated accuracy (= the C's) on that many labelled samples. A graph the
target cannot express is a figure too: ``fits`` 0 with its one-line refusal.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from snncc.targets.base import Figure, Given, Objective
from snncc.targets.kit import SnnccError
from snncc.targets.kit.search import SearchCosts, tiled_inputs, timed

LABEL = ("C target: flash and RAM (exact, from the artefact) against the part; synaptic operations per step counted in "
         "the emulator; no time or energy per trial (snncc report --energy counts instructions in QEMU)")
OBJECTIVES = {
    "flash": Objective("flash_bytes", "minimize", "bytes of constant data"),
    "ram": Objective("ram_bytes", "minimize", "bytes of state"),
    "synops": Objective("synops_per_step", "minimize", "synaptic operations per step"),
    "fits": Objective("fits", "maximize", "1 if flash and RAM fit the part, else 0"),
    "emulated_accuracy": Objective("emulated_accuracy", "maximize", "%"),
}
COLUMNS = {
    "flash": Figure("flash_bytes", "flash (B)", log=True),
    "ram": Figure("ram_bytes", "RAM (B)", log=True),
    "synops": Figure("synops_per_step", "synops / step", log=True),
    "fits": Figure("fits", "fits (1/0)"),
    "emulated_accuracy": Figure("emulated_accuracy", "emulated %"),
}
FRONT = ("flash", "synops", "fits")


@dataclass
class CFigures:
    part: str
    fits: int
    flash_bytes: int = 0
    ram_bytes: int = 0
    synops_per_step: float = 0.0
    rule: str = ""
    refusal: str = ""
    emulated_accuracy: float | None = None
    emulated_on: int = 0
    seconds: float = 0.0
    label: str = LABEL
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def synops_per_step(net, x: np.ndarray) -> float:   # noqa: ANN001 (a CNetwork)
    """Mean synaptic operations per step: every event's nonzero fan-out, summed over projections (emulator)."""
    from snncc.targets.c.emulation.emulator import emulate_network

    run = emulate_network(net, x, populations=tuple(p.name for p in net.populations))
    total = 0.0
    for q in net.projections:
        fan = (q.weights != 0).sum(axis=1).astype(np.float64)                     # per source neuron
        spikes = x if q.source < 0 else run.spikes[net.populations[q.source].name]
        total += float((np.asarray(spikes, np.float64).sum(axis=(0, 1)) * fan).sum())
    return total / max(1, x.shape[0] * x.shape[1])


class CHardware(SearchCosts):
    objectives: Mapping[str, Objective] = OBJECTIVES
    columns: Mapping[str, Figure] = COLUMNS
    front = FRONT
    label = LABEL

    def figures(self, graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,  # noqa: ANN001
                estimate_samples: int = 16, emulate_samples: int = 0) -> CFigures:
        from snncc.targets.c.artefact import csource
        from snncc.targets.c.emulation.emulator import emulate_network
        from snncc.targets.c.estimate.memory import fit, memory_record
        from snncc.targets.c.estimate.parts import DEFAULT_PART, PARTS
        from snncc.targets.c.lowering.lower import lower_network

        with timed() as clock:
            opts = self.target._options(options, "lower")
            part = PARTS[opts.mcu or DEFAULT_PART]
            try:
                net, _, _, _ = lower_network(graph, opts)
            except SnnccError as err:
                return CFigures(part["name"], 0, refusal=err.line())
            memory = memory_record(net, csource.source(net, {}))
            fitted = fit(memory, part)
            x = tiled_inputs(np.asarray(inputs), graph, net.inputs).astype(np.uint8)
            figures = CFigures(part["name"], int(fitted["fits"]), memory["flash_data_bytes"],
                               memory["ram_state_bytes"], synops_per_step(net, x[:max(1, estimate_samples)]), net.rule)
            if emulate_samples > 0:
                m = min(int(emulate_samples), int(x.shape[0]))
                counts = emulate_network(net, x[:m]).counts
                figures.emulated_accuracy = float(100.0 * np.mean(np.argmax(counts, axis=1) == np.asarray(labels[:m])))
                figures.emulated_on = m
        figures.seconds = clock.seconds
        return figures


__all__ = ["CHardware", "CFigures", "synops_per_step", "OBJECTIVES", "COLUMNS", "FRONT", "LABEL"]
