"""Which weight-scale rule to use: the paper's global w_scale, per-layer scales, or a measured choice.

scale="auto" keeps the paper's global rule (one w_scale, wgtExp 0, decays truncated as the paper states them)
unless it is measurably worse. A screen first looks for projections it would treat badly:
    outlier ratio  max|W| / median|W != 0| > 20    (one weight dictates the scale of all others)
    range used     max|W_k| * w_scale / 256 < 1/8   (a projection left with fewer than 5 bits)
    max|W| > 256                                     (w_scale would be 0)
When it flags nothing and the global rule's outputs spike and netx runs it, that is the rule. Otherwise
candidates are measured by emulating the calibration inputs and comparing every layer's per-neuron spike
counts with the float model's (in the order Loihi runs). Portable first: when a rule lava-dl netx runs as
written (``bundle/portability.py``: the global rule, per-layer scales) is live, only those compete; else --
the model itself needs what netx lacks (current biases through always-on sources, delays, a refractory
period), or no portable rule lowers with live outputs -- per-layer scales with split exponents on the
projections that have outliers (two synapse formats) and the fine rule (every synapse its finest exponent,
thresholds near 2**14 chip units, decay registers rounded to nearest: ``quantize.py``) compete too.

The cheapest live candidate (the paper's global rule where it is live; then per-layer, split, fine) is kept
unless another measures better beyond the interval: the candidate with the smallest calibration
error is measured again beside it, both in argmax agreement with the float model on ``compare``'s larger set
(``lower.py``: seeded random inputs, the count stated in the record), and it is chosen only when its 95 %
Wilson interval lies above the cheaper rule's. Otherwise the cheaper rule wins and the reason says what the
alternative would gain and cost (its cores: the mapper's lower bound). A few calibration samples tell
spike-count errors apart, not decisions. A candidate whose outputs never spike on the calibration inputs is
never chosen; when the float model's outputs are silent there, nothing can be measured and the simplest rule
that lowers is kept (the report says so).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Callable

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.targets.kit import Progress
from snncc.targets.loihi import chip
from snncc.targets.loihi.lowering.quantize import (OUTLIER_RATIO, QuantizationRecord, projection_max, projections,
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
        w = graph.node(dense).weight
        nz = w[w != 0]                                   # this line's own copy: made absolute and sorted in place
        med = float(np.median(np.abs(nz, out=nz), overwrite_input=True)) if nz.size else 0.0
        if med > 0 and m / med > OUTLIER_RATIO:
            flagged[dense] = Flag(FlagKind.OUTLIERS, f"max|W| is {m / med:.0f}x the median |W|")
        elif possible and m * np.floor(span / top) / span < MIN_RANGE:
            flagged[dense] = Flag(FlagKind.LOW_RANGE, f"uses {100 * m * np.floor(span / top) / span:.1f}% of the "
                                  "8-bit range under one global scale")
    return Screen(flagged, possible)


FINE_REASON = ("requested: fine (each synapse its finest weight exponent, threshold mantissa near 256, "
               "decay registers rounded to nearest)")
PORTABLE_RULES = ("global", "per-layer")     # one weight exponent per projection: netx runs it when 0 (portability.py)


@dataclass
class CandidateMeasure:
    """A candidate emulated on the calibration inputs against the float model.

    error: mean over layers of the per-neuron spike-count error (None when the float model's outputs
    are silent: nothing to compare); outputs_silent: the candidate's output population never spikes;
    gaps: why netx would not run the candidate's network as written (``bundle/portability.py``);
    agreement: the argmax agreement of its output spike counts with the float model's on the same
    inputs (``snncc.measure.agreement.ArgmaxAgreement.as_dict()``; None where not measured)."""

    error: float | None
    outputs_silent: bool = False
    float_silent: bool = False
    gaps: list = field(default_factory=list)
    agreement: dict | None = None

    @property
    def live(self) -> bool:
        """Measurable and alive: the float outputs spike, and so do the candidate's."""
        return self.error is not None and not self.outputs_silent

    @property
    def portable(self) -> bool:
        return not self.gaps

    @property
    def rule_portable(self) -> bool:
        """No gap the scale rule causes (the model's own needs aside)."""
        return not any(g.by_rule for g in self.gaps)


ErrorFn = Callable[[Graph | None, QuantizationRecord], CandidateMeasure]
Make = Callable[[bool], tuple[Graph | None, QuantizationRecord]]   # quantize a candidate (True: its graph too)
# the paper's rule and an alternative measured on more samples: {"samples", "inputs", "agreement": {name: ArgmaxAgreement
# as a dict}, "cores": {name: lower bound}}
CompareFn = Callable[[dict[str, QuantizationRecord]], dict]


def split_projections(record: QuantizationRecord) -> list[str]:
    """The projections the record actually split (two exponents)."""
    return sorted(p.dense for p in record.projections if p.wgt_exp_outliers is not None)


def _error_text(m: CandidateMeasure) -> str:
    if m.error is None:
        return "undefined (outputs silent in float)"
    return f"{m.error:.4f}" + (" (outputs silent)" if m.outputs_silent else "")


def choose(graph: Graph, rule: str, measure: ErrorFn, calibration: str,
           progress: Progress | None = None, compare: CompareFn | None = None,
           no_second_look: str | None = None) -> tuple[Graph, QuantizationRecord]:
    """Quantize ``graph`` under ``rule``; for "auto", decide by the screen and by measurement
    (``progress(done, total, phase)`` after each candidate; the total grows when more rules are measured).

    auto keeps to the rules netx runs as written (``PORTABLE_RULES``, checked on each candidate's
    network by ``netx_runnable``): the paper's global rule when the screen flags nothing, else the
    portable candidate with the smallest measured error. Only when no portable candidate is live
    (the model itself needs what netx lacks, or no portable rule can be lowered or keeps the outputs
    alive) are split exponents and the fine rule measured too, and the best of all is taken. A
    candidate whose outputs are silent on the calibration inputs is never chosen; when the float
    model's own outputs are silent nothing can be measured, and the first rule that lowers is kept."""
    if rule == "global":
        return quantize_graph(graph, "global", reason="requested: the paper's rule (one w_scale, wgtExp 0)")
    if rule == "per-layer":
        return quantize_graph(graph, "per-layer", reason="requested: one scale per layer, weight exponent per projection")
    if rule == "fine":
        return quantize_graph(graph, "fine", reason=FINE_REASON)
    if rule not in ("auto", "split"):
        raise SnnccError("scale must be one of global, per-layer, split, fine, auto", field="--scale")
    if compare is None:
        def compare(records: dict) -> dict:
            return {"samples": 0, "inputs": "not measured (no second look given)", "agreement": {}, "cores": {}}
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
    candidates: list[tuple[str, Make, QuantizationRecord, CandidateMeasure]] = []
    planned = [int(sc.global_possible) + 1]          # the portable rules; more when the rest are measured
    considered = [0]

    made: dict[str, tuple[Graph, QuantizationRecord]] = {}     # the first candidate's graph and record

    def consider(name: str, make: Make) -> None:
        """Quantize and measure a candidate; one that cannot be lowered (a register out of range) is left out.
        The first candidate keeps its quantized graph (the paper's rule, most often the one chosen); of the others
        only the record is kept (the quantized graph is made again if one of them is chosen)."""
        try:
            keep = not made
            gq, r = make(keep)
            candidates.append((name, make, r, measure(gq, r)))
            if keep:
                made[name] = (gq, r)
            else:
                r.forget()
        except SnnccError as ex:
            refused[name] = ex.line()
        considered[0] += 1
        if progress is not None:
            progress(considered[0], max(planned[0], considered[0]), MEASURING)

    if progress is not None:
        progress(0, planned[0], MEASURING)

    if sc.global_possible:
        consider("global", lambda out: quantize_graph(graph, "global", graph_out=out))
        if "global" in refused:
            sc.flagged["graph"] = Flag(FlagKind.GLOBAL_REFUSED, "the paper's global rule cannot be lowered")
    clean = not sc.flagged and candidates and candidates[0][3].live and candidates[0][3].portable
    # a network too large for the second look keeps the paper's rule whenever it is live: no alternative could
    # be chosen, so none is measured
    skipped = bool(no_second_look) and not clean and bool(candidates) and candidates[0][3].live
    if not clean and not skipped and not (candidates and candidates[0][3].float_silent):
        consider("per-layer", lambda out: quantize_graph(graph, "per-layer", graph_out=out))
    float_silent = any(m.float_silent for *_, m in candidates)
    portable = [c for c in candidates if c[3].live and c[3].portable]
    extended = not portable and not float_silent and not clean and not skipped
    if extended:        # the model needs what netx lacks, or no portable rule is live: measure the rest
        planned[0] = considered[0] + int(bool(outliers)) + 1
        if outliers:
            try:
                split = quantize_graph(graph, "per-layer", split=outliers, graph_out=False)[1]
            except SnnccError as ex:
                refused["split"] = ex.line()
            else:
                split.forget()
                if split_projections(split):
                    consider(f"per-layer, split exponents on {split_projections(split)}",
                             lambda out: quantize_graph(graph, "per-layer", split=outliers, graph_out=out))
        consider("fine", lambda out: quantize_graph(graph, "fine", graph_out=out))
    if not candidates:
        raise SnnccError(f"no scale rule can be lowered: {'; '.join(f'{k}: {v}' for k, v in refused.items())}",
                         field="--scale")
    float_silent = any(m.float_silent for *_, m in candidates)
    if progress is not None:
        progress(considered[0], considered[0], MEASURING)
    measures = {name: m for name, _, _, m in candidates}
    errors = {name: m.error for name, m in measures.items()}
    silent = sorted(name for name, m in measures.items() if m.outputs_silent and m.error is not None)
    live = [c for c in candidates if c[3].live]
    best_rule_portable = min((c for c in live if c[3].rule_portable), key=lambda c: c[3].error, default=None)
    significance = None
    if float_silent:
        name, make, r, m = candidates[0]        # the simplest rule that lowers: nothing to measure
        why = (f"auto: the float model's outputs are silent on the calibration inputs, so no rule can be measured; "
               f"kept '{name}', the simplest rule that lowers")
    elif skipped:
        name, make, r, m = candidates[0]
        flags = ", ".join(f"{k}: {v}" for k, v in sc.flagged.items()) or "no flags"
        why = (f"auto: {flags}; kept the paper's global rule (calibration spike-count error {m.error:.4f}): "
               f"{no_second_look}, so no other rule could be shown better beyond the interval and none was "
               "measured (--scale per-layer, split or fine asks for one)")
    elif clean:
        name, make, r, m = candidates[0]
        why = (f"auto: the paper's global rule; no outlier weights (every max|W| <= {OUTLIER_RATIO:.0f}x its median, "
               "every projection uses >= 1/8 of the 8-bit range); outputs spike on the calibration inputs "
               f"(spike-count error {m.error:.4f})")
    else:
        pool = portable or live
        if not pool:
            raise SnnccError("every scale rule leaves the outputs silent on the calibration inputs, where the float "
                             f"model's spike ({', '.join(f'{k}: {_error_text(v)}' for k, v in measures.items())}); "
                             "a bundle that never answers is not written", field="--scale")
        paper = pool[0]                                         # the cheapest: the paper's rule where it is live
        best = min(pool, key=lambda c: c[3].error)               # min keeps the first of equal errors
        scope = (f"{len(pool)} netx-runnable candidate(s) ({', '.join(c[0] for c in pool)})" if portable else
                 f"{len(pool)} live candidates (no netx-runnable rule is: "
                 + "; ".join(sorted({str(gap) for c in candidates for gap in c[3].gaps if not gap.by_rule}
                                    or {"none lowers with live outputs"})) + ")")
        flags = ", ".join(f"{k}: {v}" for k, v in sc.flagged.items()) or "no flags"
        kept = (f"'{paper[0]}' (the paper's rule)" if paper[0] == "global" else
                f"'{paper[0]}', the cheapest live rule" + (" (the global rule cannot be lowered)" if "global" in refused
                                                         else " (max|W| > 256: the global rule is impossible)"
                                                         if not sc.global_possible else ""))
        if best is paper or not best[3].error < paper[3].error:
            name, make, r, m = paper
            why = (f"auto: {flags}; kept {kept}: no other of {scope} measures a smaller spike-count error on the "
                   f"calibration inputs ({paper[3].error:.4f})")
        else:
            significance = compare({paper[0]: paper[2], best[0]: best[2]})
            empty = {"share": None, "low": None, "high": None}
            ours = significance["agreement"].get(paper[0], empty)
            theirs = significance["agreement"].get(best[0], empty)
            beyond = (theirs["low"] is not None and ours["high"] is not None and theirs["low"] > ours["high"])
            name, make, r, m = best if beyond else paper
            gain = (None if theirs["share"] is None or ours["share"] is None
                    else 100.0 * (theirs["share"] - ours["share"]))
            said = (f"'{best[0]}' {_share_text(theirs)} vs {_share_text(ours)} for '{paper[0]}' in argmax agreement with "
                    f"the float model on {significance['samples']} samples")
            cost = _cost_text(significance, paper[0], best[0])
            if not significance["samples"]:
                why = (f"auto: {flags}; kept {kept}: '{best[0]}' measures a smaller calibration spike-count error "
                       f"({best[3].error:.4f} vs {paper[3].error:.4f}) on the calibration inputs only; the second look "
                       f"was {significance['inputs']}; of {scope}")
            elif beyond:
                why = (f"auto: {flags}; chose '{best[0]}' over {kept}: it measures better beyond the 95 % interval: "
                       f"{said}{cost} (calibration spike-count error {best[3].error:.4f} vs {paper[3].error:.4f}; "
                       f"of {scope})")
            else:
                why = (f"auto: {flags}; kept {kept}: '{best[0]}' measures a smaller calibration spike-count error "
                       f"({best[3].error:.4f} vs {paper[3].error:.4f}) but not a better agreement beyond the 95 % "
                       f"interval on {significance['samples']} samples: {said}; it would gain "
                       + ("an undefined amount" if gain is None else f"{gain:+.1f} points") + f"{cost}; of {scope}")
            significance["alternative"], significance["paper"] = best[0], paper[0]
            significance["chosen"] = name
            significance["rule"] = ("an alternative to the cheaper, paper-faithful rule is chosen only when its "
                                    "agreement's 95 % Wilson interval lies above the paper's")
        if name.startswith("fine"):
            why += ("; the fine rule rounds the decay registers to nearest (the paper truncates: "
                    "int(4096 * (1 - exp(-dt / tau))))")
    # the chosen candidate's quantized graph: kept, or made again (the same record)
    g, r = made[name] if name in made else make(True)
    made.clear()
    if silent:
        why += "; left out (outputs silent on the calibration inputs): " + ", ".join(silent)
    if refused:
        why += "; left out (cannot be lowered): " + "; ".join(f"{k}: {v}" for k, v in refused.items())
    r.reason = why
    r.calibration = {"inputs": calibration, "metric": "mean |spike count difference| per neuron and sample relative "
                     "to the float model's mean count, mean over layers (None: the float outputs are silent)",
                     "errors": errors, "outputs_silent": silent, "flagged": sc.messages(), "refused": refused,
                     "chosen": name,
                     "best_netx_rule": None if best_rule_portable is None else
                     {"rule": best_rule_portable[0], "error": best_rule_portable[3].error,
                      "agreement": best_rule_portable[3].agreement},
                     "chosen_agreement": m.agreement,
                     "significance": significance}
    return g, r


def _share_text(a: dict) -> str:
    if a.get("share") is None:
        return "undefined"
    return f"{a['share']:.3f} [{a['low']:.3f}, {a['high']:.3f}]"


def _cost_text(significance: dict, paper: str, other: str) -> str:
    cores = significance.get("cores") or {}
    if cores.get(paper) is None or cores.get(other) is None:
        return ""
    return f", at least {cores[other]} core(s) against {cores[paper]} (the mapper's lower bound)"
