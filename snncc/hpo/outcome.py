"""What a trial returns to the study: accuracy and the hardware figures, each with its direction.

``accuracy`` is the selection accuracy: the best VALIDATION epoch's by default; with
``select="test"`` the best TEST epoch's, as the paper did (optimistic: the test set picks the
epoch *and* the hyper-parameters). The hardware objectives are the search target's (its
``hardware`` capability): on Loihi ``energy``, ``delay`` and ``synops`` per sample, from the compiled
model (ESTIMATES); ``cores`` from its core map; ``emulated_accuracy`` from the bit-exact emulator on
a subset (needs ``emulate_samples > 0``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from snncc.targets import DEFAULT_TARGET
from snncc.errors import SnnccError


def aliases(target: str | None = None) -> dict[str, tuple[str, ...]]:
    """``pareto``: accuracy and the front the search target declares (Loihi: accuracy, energy, cores)."""
    from snncc.hpo.hardware import SEARCH_TARGET, front_objectives

    return {"pareto": ("accuracy", *front_objectives(target or SEARCH_TARGET))}


def directions(target: str | None = None) -> dict[str, str]:
    """Objective -> "maximize" | "minimize": accuracy, and the search target's hardware objectives
    (``hardware.hardware_costs(target).objectives``; None: ``hardware.SEARCH_TARGET``, Loihi's
    emulated_accuracy, energy, cores, synops, delay; Xylo's neurons, feasible, real_time_margin, ...)."""
    from snncc.hpo.hardware import SEARCH_TARGET, hardware_costs

    costs = hardware_costs(target or SEARCH_TARGET)
    return {"accuracy": "maximize", **{name: o.direction for name, o in costs.objectives.items()}}


def parse_objectives(text: str, target: str | None = None) -> tuple[str, ...]:
    """``"accuracy,energy,cores"`` (or ``"pareto"``) -> the objective names, first one primary; the
    hardware objectives are ``target``'s (None: ``hardware.SEARCH_TARGET``)."""
    names: list[str] = []
    known = directions(target)
    alias = aliases(target)
    for part in (p.strip() for p in text.split(",")):
        for name in alias.get(part, (part,)):
            if name not in known:
                raise SnnccError(f"unknown objective {name!r} (known: {', '.join(known)}, or pareto)",
                                 field="--objectives")
            if name in names:
                raise SnnccError(f"objective {name!r} given twice", field="--objectives")
            names.append(name)
    if not names:
        raise SnnccError("give at least one objective", field="--objectives")
    return tuple(names)


@dataclass
class TrialOutcome:
    """Everything one finished trial measured (stored on the trial as the user attribute 'outcome')."""

    params: dict
    accuracy: float                      # on the selection split (see ``selected_on``)
    selected_on: str                     # "val" | "test" (optimistic)
    val_accuracy: float | None
    test_accuracy: float
    best_epoch: int
    epochs_run: int
    hardware: dict | None                # HardwareFigures.as_dict()
    checkpoint: str
    synthetic_data: bool
    worker: str
    train_seconds: float
    notes: list = field(default_factory=list)
    target: str = DEFAULT_TARGET                # whose hardware figures ``hardware`` holds (studies before it: Loihi)

    def as_dict(self) -> dict:
        return asdict(self)

    def value(self, name: str) -> float:
        from snncc.hpo.hardware import hardware_costs

        hw = self.hardware or {}
        if name == "accuracy":
            return float(self.accuracy)
        v = hw.get(hardware_costs(self.target).objectives[name].key)
        if v is None:
            raise SnnccError(f"objective {name!r} needs the hardware figures"
                             + (" with --emulate > 0" if name == "emulated_accuracy" else ""), field="--objectives")
        return float(v)
