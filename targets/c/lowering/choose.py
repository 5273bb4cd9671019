"""``--rule auto``: the weight rule chosen by measured agreement with the float graph.

Every candidate rule (``options.CANDIDATES``) is quantized and run in the bit-exact emulator on the same seeded
calibration inputs (random spikes of density 0.08, the artefact's own length; SYNTHETIC) beside the float graph;
each gets its argmax agreement (``kit.agreement``'s one rule) and its per-sample hits. The default is
``per-neuron`` (int8, the finest int8 scales); ``auto`` leaves it only for a candidate that agrees better on
the same samples by a paired one-sided sign test at p < ``AUTO_P`` (more samples it gets right that the default
gets wrong than the reverse), taking the best such candidate (the smaller weight flash on a tie), among the
candidates whose constant data (weights and per-neuron constants) fit the part's flash (``--mcu``): a rule that
cannot be deployed on the part is measured and shown, never chosen. So int16 weights (twice the flash) are used
where, and only where, they are measured to be needed and fit.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.c.lowering.quantize import quantize
from snncc.targets.c.lowering.structure import Structure
from snncc.targets.c.options import AUTO_P, CALIBRATION_DENSITY, CALIBRATION_SAMPLES, CANDIDATES, RULE_BITS

DEFAULT_RULE = "per-neuron"
NEURON_STEP_BUDGET = 1 << 24        # calibration samples x steps x neurons at most (a large conv net gets fewer)
MIN_SAMPLES = 64


@dataclass
class Selection:
    """What ``auto`` measured and chose (or the rule given)."""

    rule: str
    reason: str
    samples: int = 0
    inputs: str = ""
    candidates: dict[str, dict[str, Any]] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {"rule": self.rule, "reason": self.reason, "samples": self.samples, "inputs": self.inputs,
                "candidates": self.candidates}


def calibration_samples(neurons: int, steps: int) -> int:
    return int(max(MIN_SAMPLES, min(CALIBRATION_SAMPLES, NEURON_STEP_BUDGET // max(1, neurons * steps))))


def choose(st: Structure, graph, rule: str, steps: int, seed: int, flash_limit: int | None = None,
           part: str = "") -> Selection:
    """The rule to lower with: ``rule`` itself, or for "auto" the measured choice (module doc); ``flash_limit``:
    the part's flash in bytes (``part`` names it)."""
    if rule != "auto":
        return Selection(rule, "given (--rule)")
    from snncc.targets.kit.agreement import argmax_agreement, argmax_hits, random_inputs, sign_test
    from snncc.targets.c.artefact.csource import source
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.estimate.memory import const_bytes
    from snncc.targets.kit.reference import float_counts

    neurons = sum(p.op.n for p in st.populations)
    samples = calibration_samples(neurons, steps)
    x = random_inputs(samples, steps, st.inputs, CALIBRATION_DENSITY, seed)
    ref = float_counts(graph, x)
    hits: dict[str, np.ndarray] = {}
    table: dict[str, dict[str, Any]] = {}
    for name in CANDIDATES:
        net = quantize(st, name, steps)
        counts = emulate_network(net, x).counts
        hits[name] = argmax_hits(ref, counts)
        agreement = argmax_agreement(ref, counts)
        data = const_bytes(source(net, {}))
        table[name] = {"agreement": agreement.share, "decided": agreement.decided, "agreeing": agreement.agreeing,
                       "bits": RULE_BITS[name], "weight_bytes": data["weights"],
                       "flash_data_bytes": data["weights"] + data["constants"],
                       "fits": flash_limit is None or data["weights"] + data["constants"] <= flash_limit}
    base = hits[DEFAULT_RULE]
    winners = []
    for name in CANDIDATES:
        if name == DEFAULT_RULE:
            continue
        better = int(np.count_nonzero(hits[name] & ~base))
        worse = int(np.count_nonzero(~hits[name] & base))
        p = sign_test(better, worse)
        table[name]["vs_default"] = {"better": better, "worse": worse, "p": p}
        if p < AUTO_P and table[name]["fits"]:
            winners.append(name)
    inputs = (f"{samples} seeded random spike trains (density {CALIBRATION_DENSITY:g}, seed {seed}), {steps} steps "
              "(SYNTHETIC)")
    if not winners:
        unfit = [n for n in CANDIDATES if n != DEFAULT_RULE and table[n]["vs_default"]["p"] < AUTO_P
                 and not table[n]["fits"]]
        why = (f"{' and '.join(unfit)} agreed better (sign test p < {AUTO_P:g}) but would not fit "
               f"{part or 'the part'}'s flash ({flash_limit:,} bytes); {DEFAULT_RULE} (int8) fits" if unfit else
               f"no rule agreed better than {DEFAULT_RULE} (int8) by a paired sign test at p < {AUTO_P:g}")
        return Selection(DEFAULT_RULE, why, samples, inputs, table)
    best = max(winners, key=lambda n: (table[n]["agreeing"], -table[n]["weight_bytes"]))
    v = table[best]["vs_default"]
    return Selection(best, f"agrees better than {DEFAULT_RULE} (int8) on the calibration samples: +{v['better']} / "
                     f"-{v['worse']} samples, sign test p = {v['p']:.2g} < {AUTO_P:g}", samples, inputs, table)


def lowered_network(st: Structure, graph, rule: str, steps: int, seed: int, flash_limit: int | None = None,
                    part: str = ""):
    """(the ``CNetwork``, its ``Selection``)."""
    chosen = choose(st, graph, rule, steps, seed, flash_limit, part)
    return quantize(st, chosen.rule, steps), chosen


__all__ = ["Selection", "choose", "lowered_network", "calibration_samples", "DEFAULT_RULE"]
