"""What a trial's model costs on the search's target, through the target's ``hardware`` capability.

The target lowers the trial's checkpoint and measures or ESTIMATEs its cost on held-out samples
(Loihi 1: cores, synaptic ops, energy and delay per sample from Davies et al. 2018 Table 2 costs --
an ESTIMATE, not a measurement -- and, optionally, the bit-exact emulated accuracy on a subset);
``objectives`` says which of its figures a search may optimise and in which direction.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets import DEFAULT_TARGET

if TYPE_CHECKING:
    from collections.abc import Mapping

    import numpy as np

    from snncc.targets.base import Figure, HardwareCosts, HardwareFigures

SEARCH_TARGET = DEFAULT_TARGET     # the target a study is costed on unless it names one (the registry's default)


@lru_cache(maxsize=None)
def hardware_costs(target: str = SEARCH_TARGET) -> HardwareCosts:
    """The ``hardware`` capability of the registered target ``target`` (refused in one line without it;
    asked once per process: a report reads it for every trial)."""
    from snncc.targets import capability, get_target

    return capability(get_target(target), "hardware")()


def report_columns(target: str = SEARCH_TARGET) -> dict[str, Figure]:
    """Name -> ``Figure``: the figures ``target``'s ``hardware`` capability declares for a report, in column
    order (a target that declares none: one column per objective, headed by its name and unit)."""
    from snncc.targets.base import Figure

    costs = hardware_costs(target)
    declared = getattr(costs, "columns", None)
    if declared:
        return dict(declared)
    return {name: Figure(o.key, f"{name} {o.unit}") for name, o in costs.objectives.items()}


def front_objectives(target: str = SEARCH_TARGET) -> tuple[str, ...]:
    """The hardware objectives ``target``'s Pareto front weighs beside accuracy (declared by its ``hardware``
    capability; a target that declares none: every objective but emulated accuracy)."""
    costs = hardware_costs(target)
    declared = getattr(costs, "front", None)
    if declared:
        return tuple(declared)
    return tuple(name for name in costs.objectives if name != "emulated_accuracy")


def shown_figure(value: float | None, column: Figure) -> str:
    """A figure as the report shows it: stored value x the column's scale; a heading in % with two
    decimals, others with four significant digits; "-" when not measured."""
    if value is None:
        return "-"
    v = float(value) * column.scale
    return f"{v:.2f}" if column.heading.endswith("%") else f"{v:,.4g}"


def hardware_summary(hardware: dict | None, target: str = SEARCH_TARGET) -> str:
    """One line of a trial's measured figures, headed as ``target``'s report columns (what ``hpo run``
    prints per trial): ``cores 2, synops/sample 1,000, energy uJ (EST.) 1.5``."""
    hw = hardware or {}
    return ", ".join(f"{column.heading} {shown_figure(hw[column.key], column)}"
                     for column in report_columns(target).values() if hw.get(column.key) is not None)


def hardware_figures(checkpoint: str | Path, inputs: np.ndarray, labels: np.ndarray, energy_samples: int = 16,
                     emulate_samples: int = 0, target: str = SEARCH_TARGET,
                     options: Mapping[str, object] | None = None) -> HardwareFigures:
    """Lower ``checkpoint`` for ``target`` with its lower ``options`` (compile's flags, e.g.
    ``allow_reset_change``); its figures on the first ``energy_samples`` of ``inputs`` (B, T, C), ordered by
    the caller; ``emulate_samples`` > 0: also the deployed accuracy on that many."""
    from snncc.frontends import load_model

    graph = load_model(Path(checkpoint))
    return hardware_costs(target).figures(graph, inputs, labels, {**(options or {}), "source": str(checkpoint)},
                                          estimate_samples=energy_samples, emulate_samples=emulate_samples)
