"""Which weight-scale rule to use: the paper's global w_scale, per-layer scales, or a measured choice.

scale="auto" keeps the paper's global rule unless a screen finds projections it would treat badly:
    outlier ratio  max|W| / median|W != 0| > 20    (one weight dictates the scale of all others)
    range used     max|W_k| * w_scale / 256 < 1/8   (a projection left with fewer than 5 bits)
    max|W| > 256                                     (w_scale would be 0)
When flagged, candidates are measured by emulating calibration inputs and comparing every layer's
per-neuron spike counts with the float model's (in the order Loihi runs): the global rule, per-layer scales,
per-layer scales with split exponents on the projections that have outliers (the outliers keep
the exponent that fits them, the bulk of the weights gets a finer one: two synapse formats), and
the fine rule (every synapse its own finest exponent, thresholds near 2**14 chip units, decay
registers rounded to nearest: ``quantize.py``) at the scales s * k, k in FINE_STEPS (one octave: the
same precision, each weight rounded differently; which rounding errors cancel is measured, not
assumed). The candidate with the smallest measured error
wins (ties go to the one listed first, the simpler), so auto is never worse, on the calibration
inputs, than any rule it tried.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.progress import Progress
from snncc.targets.loihi import chip
from snncc.targets.loihi.lowering.quantize import (FINE_STEPS, OUTLIER_RATIO, QuantizationRecord, projection_max, projections,
                                          quantize_graph)

MIN_RANGE = 1.0 / 8.0
MEASURING = "measuring scale candidates"


class FlagKind(Enum):
    """Why the screen flagged a projection (or the graph)."""

    OUTLIERS = "outliers"                # max|W| > OUTLIER_RATIO x the median |W != 0|: split exponents may help
    LOW_RANGE = "low range"              # under one global scale it uses < MIN_RANGE of the 8-bit range
    GLOBAL_REFUSED = "global refused"    # the paper's global rule cannot be lowered (a register out of range)


@dataclass(frozen=True)
class Flag:
    """One flag: its kind, and the message printed in the record's reason."""

    kind: FlagKind
    message: str

    def __str__(self) -> str:
        return self.message


@dataclass
class Screen:
    flagged: dict[str, Flag]     # dense (or "graph") -> why
    global_possible: bool

    def of_kind(self, kind: FlagKind) -> set[str]:
        """The flagged names whose flag is ``kind``."""
        return {name for name, flag in self.flagged.items() if flag.kind is kind}

    def messages(self) -> dict[str, str]:
        """name -> message, as recorded in the calibration record."""
        return {name: flag.message for name, flag in self.flagged.items()}


def screen(graph: Graph) -> Screen:
    flagged: dict[str, Flag] = {}
    maxima = {d: projection_max(graph, d, lif) for d, lif in projections(graph)}
    top = max(maxima.values())
    span = chip.WEIGHT_SPAN
    possible = 0 < top <= span
    for dense, m in maxima.items():
        w = np.abs(graph.node(dense).weight)
        nz = w[w > 0]
        med = float(np.median(nz)) if nz.size else 0.0
        if med > 0 and m / med > OUTLIER_RATIO:
            flagged[dense] = Flag(FlagKind.OUTLIERS, f"max|W| is {m / med:.0f}x the median |W|")
        elif possible and m * np.floor(span / top) / span < MIN_RANGE:
            flagged[dense] = Flag(FlagKind.LOW_RANGE, f"uses {100 * m * np.floor(span / top) / span:.1f}% of the "
                                  "8-bit range under one global scale")
    return Screen(flagged, possible)


FINE_REASON = ("requested: fine (each synapse its finest weight exponent, threshold mantissa near 256, "
               "decay registers rounded to nearest)")
ErrorFn = Callable[[Graph, QuantizationRecord], float]


def split_projections(record: QuantizationRecord) -> list[str]:
    """The projections the record actually split (two exponents)."""
    return sorted(p.dense for p in record.projections if p.wgt_exp_outliers is not None)


def choose(graph: Graph, rule: str, measure: ErrorFn, calibration: str,
           progress: Progress | None = None) -> tuple[Graph, QuantizationRecord]:
    """Quantize ``graph`` under ``rule``; for "auto", decide by the screen and by measured error
    (``progress(done, total, phase)`` after each candidate)."""
    if rule == "global":
        return quantize_graph(graph, "global", reason="requested: the paper's rule (one w_scale, wgtExp 0)")
    if rule == "per-layer":
        return quantize_graph(graph, "per-layer", reason="requested: one scale per layer, weight exponent per projection")
    if rule == "fine":
        return quantize_graph(graph, "fine", reason=FINE_REASON)
    if rule not in ("auto", "split"):
        raise SnnccError("scale must be one of global, per-layer, split, fine, auto", field="--scale")
    sc = screen(graph)
    outliers = sc.of_kind(FlagKind.OUTLIERS)
    if rule == "split":
        g, r = quantize_graph(graph, "per-layer", split=outliers)
        done = split_projections(r)
        r.reason = (f"requested: per-layer scales, split exponents on {done}" if done else
                    "requested split, but no projection has outliers that a finer exponent would help "
                    f"(max|W| > {OUTLIER_RATIO:.0f}x its median): per-layer scales")
        return g, r
    refused: dict[str, str] = {}
    if sc.global_possible and not sc.flagged:
        try:
            return quantize_graph(graph, "global", reason="auto: the paper's global rule; no outlier weights (every "
                                  f"max|W| <= {OUTLIER_RATIO:.0f}x its median, every projection uses >= 1/8 of the "
                                  "8-bit range)")
        except SnnccError as ex:   # e.g. a threshold mantissa beyond 17 bits: measure the other rules
            refused["global"] = ex.line()
            sc.flagged["graph"] = Flag(FlagKind.GLOBAL_REFUSED, "the paper's global rule cannot be lowered")
            sc.global_possible = False
    candidates: list[tuple[str, Graph, QuantizationRecord, float]] = []
    planned = int(sc.global_possible) + 1 + int(bool(outliers)) + len(FINE_STEPS)
    considered = [0]

    def consider(name: str, make: Callable[[], tuple[Graph, QuantizationRecord]]) -> None:
        """Quantize and measure a candidate; one that cannot be lowered (a register out of range) is left out."""
        try:
            g, r = make()
            candidates.append((name, g, r, measure(g, r)))
        except SnnccError as ex:
            refused[name] = ex.line()
        considered[0] += 1
        if progress is not None:
            progress(considered[0], planned, MEASURING)

    if progress is not None:
        progress(0, planned, MEASURING)

    if sc.global_possible:
        consider("global", lambda: quantize_graph(graph, "global"))
    consider("per-layer", lambda: quantize_graph(graph, "per-layer"))
    if outliers:
        try:
            split = quantize_graph(graph, "per-layer", split=outliers)
        except SnnccError as ex:
            refused["split"] = ex.line()
        else:
            if split_projections(split[1]):
                consider(f"per-layer, split exponents on {split_projections(split[1])}", lambda: split)
    for step in FINE_STEPS:
        consider("fine" if step == 1.0 else f"fine x{step:g}", lambda step=step: quantize_graph(graph, "fine", fine_step=step))
    if not candidates:
        raise SnnccError(f"no scale rule can be lowered: {'; '.join(f'{k}: {v}' for k, v in refused.items())}",
                         field="--scale")
    if progress is not None:
        progress(planned, planned, MEASURING)
    errors = {name: err for name, _, _, err in candidates}
    paper = errors.get("global")
    name, g, r, err = min(candidates, key=lambda c: c[3])   # min keeps the first of equal errors
    versus = (f" vs {paper:.4f} under the paper's global rule" if paper is not None else
              " (the global rule cannot be lowered)" if "global" in refused else
              " (the global rule is impossible: max|W| > 256)" if not sc.global_possible else
              " (the global rule cannot be lowered)")
    why = (f"auto: {', '.join(f'{k}: {v}' for k, v in sc.flagged.items())}; chose '{name}' by measured "
           f"spike-count error {err:.4f}{versus}, the smallest of {len(errors)} candidates")
    if refused:
        why += "; left out (cannot be lowered): " + "; ".join(f"{k}: {v}" for k, v in refused.items())
    r.reason = why
    r.calibration = {"inputs": calibration, "metric": "mean |spike count difference| per neuron and sample relative "
                     "to the float model's mean count, mean over layers", "errors": errors, "flagged": sc.messages(),
                     "refused": refused}
    return g, r
