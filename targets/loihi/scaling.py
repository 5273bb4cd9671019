"""Which weight-scale rule to use: the paper's global w_scale, per-layer scales, or a measured choice.

scale="auto" keeps the paper's global rule unless a screen finds projections it would treat badly:
    outlier ratio  max|W| / median|W != 0| > 20    (one weight dictates the scale of all others)
    range used     max|W_k| * w_scale / 256 < 1/8   (a projection left with fewer than 5 bits)
    max|W| > 256                                     (w_scale would be 0)
When flagged, candidates are measured by emulating calibration inputs and comparing every layer's
per-neuron spike counts with the float model's (in the order Loihi runs): the global rule, per-layer scales,
and per-layer scales with split exponents on the projections that have outliers (the outliers keep
the exponent that fits them, the bulk of the weights gets a finer one: two synapse formats). A
candidate replaces the paper's rule only if it cuts the error by >= 25 %.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.passes.quantize import OUTLIER_RATIO, QuantizationRecord, projection_max, projections, quantize_graph

OUTLIER_REASON = "max|W| is"
MIN_RANGE = 1.0 / 8.0
IMPROVEMENT = 0.75          # a candidate must cut the measured error by at least 25 %


@dataclass
class Screen:
    flagged: dict[str, str]      # dense -> why
    global_possible: bool


def screen(graph: Graph) -> Screen:
    flagged: dict[str, str] = {}
    maxima = {d: projection_max(graph, d, lif) for d, lif in projections(graph)}
    top = max(maxima.values())
    possible = 0 < top <= 256
    for dense, m in maxima.items():
        w = np.abs(graph.node(dense).weight)
        nz = w[w > 0]
        med = float(np.median(nz)) if nz.size else 0.0
        if med > 0 and m / med > OUTLIER_RATIO:
            flagged[dense] = f"{OUTLIER_REASON} {m / med:.0f}x the median |W|"
        elif possible and m * np.floor(256.0 / top) / 256.0 < MIN_RANGE:
            flagged[dense] = f"uses {100 * m * np.floor(256.0 / top) / 256.0:.1f}% of the 8-bit range under one global scale"
    return Screen(flagged, possible)


ErrorFn = Callable[[Graph, QuantizationRecord], float]


def choose(graph: Graph, rule: str, measure: ErrorFn, calibration: str) -> tuple[Graph, QuantizationRecord]:
    """Quantize ``graph`` under ``rule``; for "auto", decide by the screen and by measured error."""
    if rule == "global":
        return quantize_graph(graph, "global", reason="requested: the paper's rule (one w_scale, wgtExp 0)")
    if rule == "per-layer":
        return quantize_graph(graph, "per-layer", reason="requested: one scale per layer, weight exponent per projection")
    if rule not in ("auto", "split"):
        raise SnnccError("scale must be one of global, per-layer, split, auto", field="--scale")
    sc = screen(graph)
    outliers = {d for d, why in sc.flagged.items() if why.startswith(OUTLIER_REASON)}
    if rule == "split":
        return quantize_graph(graph, "per-layer", split=outliers, reason=(
            f"requested: per-layer scales, split exponents on the projections with outliers {sorted(outliers)}"
            if outliers else f"requested split, but no projection has outliers (max|W| > {OUTLIER_RATIO:.0f}x its "
            "median): per-layer scales"))
    if sc.global_possible and not sc.flagged:
        return quantize_graph(graph, "global", reason="auto: the paper's global rule; no outlier weights (every "
                              f"max|W| <= {OUTLIER_RATIO:.0f}x its median, every projection uses >= 1/8 of the 8-bit range)")
    candidates: list[tuple[str, Graph, QuantizationRecord, float]] = []
    if sc.global_possible:
        g, r = quantize_graph(graph, "global")
        candidates.append(("global", g, r, measure(g, r)))
    g, r = quantize_graph(graph, "per-layer")
    candidates.append(("per-layer", g, r, measure(g, r)))
    if outliers:
        g, r = quantize_graph(graph, "per-layer", split=outliers)
        if any(p.wgt_exp_outliers is not None for p in r.projections):
            candidates.append((f"per-layer, split exponents on {sorted(outliers)}", g, r, measure(g, r)))
    errors = {name: err for name, _, _, err in candidates}
    paper = errors.get("global")
    name, g, r, err = min(candidates, key=lambda c: c[3])
    if paper is not None and not (err <= IMPROVEMENT * paper and paper > 0):
        name, g, r, err = candidates[0]
        why = (f"auto: kept the paper's global rule; no candidate cut its measured spike-count error ({paper:.4f}) "
               f"by {100 * (1 - IMPROVEMENT):.0f} %")
    else:
        why = (f"auto: {', '.join(f'{k}: {v}' for k, v in sc.flagged.items())}; chose '{name}' by measured "
               f"spike-count error {err:.4f}" + (f" vs {paper:.4f} under the paper's global rule" if paper is not None
                                                 else " (the global rule is impossible: max|W| > 256)"))
    r.reason = why
    r.calibration = {"inputs": calibration, "metric": "mean |spike count difference| per neuron and sample relative "
                     "to the float model's mean count, mean over layers", "errors": errors, "flagged": sc.flagged}
    return g, r
