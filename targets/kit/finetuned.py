"""A fine-tuned artefact: what a target's ``finetune`` capability returns (``base.FinetunedArtefact``).

The target lowers the model, trains the lowered parameters through its integer arithmetic with the
shared engine (``kit.finetuning``) and builds its artefact from the result; this wrapper writes and
summarises that artefact as ``lower``'s would, adds the ``finetune`` entry (``finetune_metadata`` and
the engine's record) and prints the record's lines after the artefact's. ``adapted`` is the fine-tuned
parameters read back as a float IR graph (what ``--finetune-out`` writes); a target whose artefact has
no faithful float reading gives ``refusal`` instead, the line ``--finetune-out`` is refused with.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from snncc.errors import SnnccError

if TYPE_CHECKING:
    from snncc.ir.graph import Graph
    from snncc.targets.base import Artefact

TEACHER = "the float graph as trained (its own reset)"


def finetune_metadata(record: Any) -> dict[str, Any]:
    """What an artefact records of its fine-tuning (JSON-ready) from the engine's ``FinetuneRecord``."""
    return {"finetuned": True, "inputs": record.inputs, "seed": record.inputs["seed"], "steps": record.steps,
            "kept_epoch": record.kept_epoch, "agreement_before": record.held_out_before,
            "agreement_after": record.held_out_after, "teacher": TEACHER}


def finetune_entry(record: Any) -> dict[str, Any]:
    """The ``finetune`` entry of a summary or manifest: ``finetune_metadata`` plus the engine's whole record."""
    return {**finetune_metadata(record), "record": record.as_dict()}


@dataclass
class FinetunedArtefact:
    """``artefact`` (the fine-tuned artefact, written as ``lower``'s: it already carries its ``finetune`` entry
    where its format records one), ``record`` (the engine's ``FinetuneRecord``), ``adapted`` (the float graph
    of the fine-tuned parameters) or ``refusal`` (why there is none)."""

    artefact: Artefact
    record: Any
    adapted: Graph | None = None
    refusal: str = ""

    def write(self, path: Any) -> None:
        self.artefact.write(path)

    def summary(self) -> dict[str, Any]:
        return {**self.artefact.summary(), "finetune": self.finetune_record()}

    def render_text(self, console: Any) -> None:
        render = getattr(self.artefact, "render_text", None)
        if callable(render):
            render(console)
        for line in self.record.lines():
            console.print(line, markup=False)

    def adapted_graph(self) -> Graph:
        if self.adapted is None:
            raise SnnccError(self.refusal or "this target's fine-tuned artefact has no float graph to write",
                             field="--finetune-out")
        return self.adapted

    def finetune_record(self) -> dict[str, Any]:
        return finetune_entry(self.record)


__all__ = ["FinetunedArtefact", "finetune_metadata", "finetune_entry", "TEACHER"]
