"""The record every target's ``check`` and ``agree`` return, so that every check reads the same way.

A check runs the float graph and the written artefact on the same inputs and compares their output
spike counts by the one agreement rule (``kit.agreement``). Between the two, a target runs the
*stages* it can build, each differing from the one before by one cause of loss; every stage is compared
with the float graph as trained on the same samples. The loss of a stage is the agreement it loses
against the stage before, in points (100 x the share); stages are successive, so the losses are not
independent and may be negative where a later stage compensates.

Causes are named the same for every target (``CAUSES``), so a table of targets lines up:

    reset        the reset rule changed (a zero-reset model deployed with subtraction, or the reverse)
    weights      weights (and thresholds) on the chip's grid: quantization and the rule's placement
    decays       decays and state on the chip's grid: decay rounding, state truncation
    saturation   a register or an event count capped: overflow, clipping
    timing       the order or delays the chip runs differ from the model's
    other        anything else the target names (Jetson: float32 arithmetic)

A target states which causes can occur on it (``possible``); a cause that cannot is shown as "—", one
that can but did not as 0. ``details`` holds the target's own figures (JSON) and ``detail_lines`` how
they print, after the common part.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from snncc.measure.agreement import UNDECIDED_RULE, ArgmaxAgreement

CAUSES = ("reset", "weights", "decays", "saturation", "timing", "other")
CAUSE_TITLES = {"reset": "reset change", "weights": "weight quantization", "decays": "decays / state rounding",
                "saturation": "saturation", "timing": "timing", "other": "other"}
REFERENCE = "the float graph as trained (its own reset)"
CANNOT = "—"


@dataclass
class Stage:
    """One stage of a check: ``key`` (the target's name for it), ``label`` (what runs), ``cause`` (the one of
    ``CAUSES`` that stepping into it from the stage before measures; None for a stage that is a reference),
    its ``agreement`` with the float graph as trained (``ArgmaxAgreement.as_dict()``) and, with labels,
    its ``accuracy``."""

    key: str
    label: str
    cause: str | None
    agreement: dict[str, Any]
    accuracy: float | None = None

    @property
    def share(self) -> float | None:
        found = self.agreement.get("share")
        return None if found is None else float(found)


def stage(key: str, label: str, cause: str | None, agreement: ArgmaxAgreement,
          accuracy: float | None = None) -> Stage:
    """A ``Stage`` from an ``ArgmaxAgreement`` (``cause`` one of ``CAUSES`` or None)."""
    if cause is not None and cause not in CAUSES:
        raise ValueError(f"unknown cause {cause!r} (one of {', '.join(CAUSES)})")
    return Stage(key, label, cause, agreement.as_dict(), accuracy)


def losses_by_cause(stages: Sequence[Stage], possible: Iterable[str]) -> dict[str, float | None]:
    """Points lost per cause: each stage's share subtracted from the share before it (1.0 before the first
    stage, which is the float graph itself), summed per cause; a cause in ``possible`` without a stage is 0,
    one not in ``possible`` None; None too where an agreement on the way is undefined."""
    can = set(possible)
    out: dict[str, float | None] = {c: (0.0 if c in can else None) for c in CAUSES}
    previous: float | None = 1.0
    for s in stages:
        share = s.share
        if s.cause is not None:
            if s.cause not in can:
                raise ValueError(f"stage {s.key!r} measures {s.cause!r}, which the target does not list as possible")
            have = out[s.cause]
            out[s.cause] = None if (share is None or previous is None or have is None) else have + 100.0 * (previous - share)
        previous = share
    return out


@dataclass
class CheckReport:
    """What a written artefact loses against the float graph as trained, and why (module doc).

    ``argmax_agreement``: the artefact's share (None: undefined), ``argmax`` its ``ArgmaxAgreement``;
    ``accuracy``: with labels ``{"float": .., "artefact": ..}`` (fractions), else None; ``ceiling``: the float
    graph against itself with ``noise`` weight noise (``{"noise", "argmax_agreement", "argmax"}``) or None;
    ``causes``: ``losses_by_cause``; ``possible``: the causes that can occur on the target."""

    target: str
    inputs: str
    samples: int
    steps: int
    argmax_agreement: float | None
    argmax: dict[str, Any]
    count_correlation: float | None
    stages: list[Stage]
    causes: dict[str, float | None]
    possible: list[str]
    accuracy: dict[str, float] | None = None
    ceiling: dict[str, Any] | None = None
    reference: str = REFERENCE
    undecided_rule: str = UNDECIDED_RULE
    liveness: dict[str, Any] = field(default_factory=dict)
    flagged: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    details: dict[str, Any] = field(default_factory=dict)
    detail_lines: list[str] = field(default_factory=list)

    @property
    def total_points(self) -> float | None:
        return None if self.argmax_agreement is None else 100.0 * (1.0 - self.argmax_agreement)

    def as_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("detail_lines")
        out["total_points"] = self.total_points
        return out

    def lines(self) -> list[str]:
        out = [f"{self.target} artefact vs {self.reference}, on {self.inputs}: {self.samples} samples x "
               f"{self.steps} steps",
               f"  argmax agreement   {ArgmaxAgreement(**self.argmax).text()}"]
        if self.ceiling is not None:
            c = self.ceiling
            shown = "undefined" if c.get("argmax_agreement") is None else f"{c['argmax_agreement']:.3f}"
            out.append(f"                     ceiling: the float graph with {100 * c['noise']:g} % weight noise agrees "
                       f"{shown} with itself")
        corr = "undefined (constant counts)" if self.count_correlation is None else f"{self.count_correlation:.4f}"
        out.append(f"  count correlation  {corr}")
        if self.accuracy is not None:
            out.append(f"  accuracy           float {100 * self.accuracy['float']:.2f} %, artefact "
                       f"{100 * self.accuracy['artefact']:.2f} %")
        if len(self.stages) > 1:
            out.append("  stages (agreement with the float graph as trained):")
            width = max(len(s.key) for s in self.stages)
            for s in self.stages:
                figure = "undefined" if s.share is None else f"{s.share:.3f}"
                acc = "" if s.accuracy is None else f", accuracy {100 * s.accuracy:.2f} %"
                out.append(f"    {s.key:<{width}}  {figure}{acc}  {s.label}")
        cells = []
        for cause in CAUSES:
            value = self.causes.get(cause)
            if cause not in self.possible:
                cells.append(f"{CAUSE_TITLES[cause]} {CANNOT}")
            else:
                cells.append(f"{CAUSE_TITLES[cause]} " + ("undefined" if value is None else f"{value:+.1f}"))
        total = "undefined" if self.total_points is None else f"{self.total_points:+.1f}"
        out.append(f"  loss by cause (agreement points): {', '.join(cells)}; total {total}")
        out += [f"  {line}" for line in self.detail_lines]
        out += [f"  liveness: {line}" for line in self.flagged]
        out += [f"  warning: {line}" for line in self.warnings]
        out += [f"  note: {line}" for line in self.notes]
        return out

    def render_text(self, console: Any) -> None:
        for line in self.lines():
            console.print(line, markup=False, highlight=False, soft_wrap=True)


def accuracy_pair(float_prediction: Any, artefact_prediction: Any, labels: Any) -> dict[str, float]:
    """``{"float": .., "artefact": ..}``: the share of correct predictions of each (fractions)."""
    import numpy as np

    lab = np.asarray(labels).reshape(-1)
    return {"float": float(np.mean(np.asarray(float_prediction).reshape(-1) == lab)),
            "artefact": float(np.mean(np.asarray(artefact_prediction).reshape(-1) == lab))}


def ceiling_record(agreement: ArgmaxAgreement, noise: float) -> dict[str, Any]:
    """The ``ceiling`` entry of a ``CheckReport``."""
    return {"noise": float(noise), "argmax_agreement": agreement.share, "argmax": agreement.as_dict()}


def merged_notes(*groups: Iterable[str] | None) -> list[str]:
    """Notes in order, each once."""
    seen: dict[str, None] = {}
    for group in groups:
        for note in group or ():
            seen.setdefault(str(note), None)
    return list(seen)


def report_from(target: str, *, inputs: str, samples: int, steps: int, artefact: ArgmaxAgreement,
                count_correlation: float | None, stages: Sequence[Stage], possible: Iterable[str],
                accuracy: Mapping[str, float] | None = None, ceiling: dict[str, Any] | None = None,
                **rest: Any) -> CheckReport:
    """A ``CheckReport`` with ``causes`` computed from ``stages`` (``losses_by_cause``)."""
    can = [c for c in CAUSES if c in set(possible)]
    return CheckReport(target=target, inputs=inputs, samples=int(samples), steps=int(steps),
                       argmax_agreement=artefact.share, argmax=artefact.as_dict(),
                       count_correlation=count_correlation, stages=list(stages),
                       causes=losses_by_cause(stages, can), possible=can,
                       accuracy=None if accuracy is None else dict(accuracy), ceiling=ceiling, **rest)


__all__ = ["CAUSES", "CAUSE_TITLES", "CANNOT", "REFERENCE", "CheckReport", "Stage", "stage", "losses_by_cause",
           "accuracy_pair", "ceiling_record", "merged_notes", "report_from"]
