"""``snncc check --target loihi --data``: what the written bundle costs on a labelled data set, and why.

The float graph as trained, the stages between it and the bundle (``stages.py``: reset change, Loihi's
order, quantized parameters in float, the bundle's integers with wide registers, a relayed bundle's
network without relays) and the bundle as written, run again in the bit-exact emulator, on the same
inputs. The record is the kit's ``CheckReport``: argmax agreement with the float graph and its accuracy
per stage, the loss by cause (``kit.checks.CAUSES``); Loihi's own figures (accuracy per stage under its
former names, per-layer spike agreement, overflow counts, timing, scale rule and reason) are its
``details`` and ``detail_lines``. Agreements follow the kit's one rule (samples whose float output has no
single winner are left out and counted); liveness is measured for every population in float and on
the bundle.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit import SnnccError
from snncc.targets.kit.checks import CheckReport
from snncc.targets.loihi.options import STREAM_GAP, LoihiOptions


def check_bundle(graph: Graph, path: str | Path, inputs: np.ndarray, labels: np.ndarray, options: LoihiOptions, *,
                 data: str | None = None, synthetic: bool = False,
                 progress: Callable[[int], None] | None = None) -> CheckReport:
    """Measure the written bundle at ``path`` against ``graph`` on ``inputs`` (N, T, C) 0/1 with ``labels`` (N,);
    ``options.stream``: the paper's protocol (one stream, ``STREAM_GAP`` blank steps between samples);
    ``progress(n)`` after each chunk."""
    from snncc.targets.kit.agreement import argmax_agreement, count_correlation
    from snncc.targets.kit.checks import accuracy_pair, report_from
    from snncc.targets.loihi.checks.stages import (POSSIBLE, common_notes, kit_stages, liveness_fields, measure,
                                                   quantization_of, timing_mode)
    from snncc.targets.loihi.checks.written import open_bundle
    from snncc.targets.loihi.emulation.emulator import check_inputs

    bundle = open_bundle(path, graph)
    x_all = check_inputs(inputs, bundle.network.input_width, source=data)
    labels = np.asarray(labels).reshape(-1)
    if labels.shape[0] != x_all.shape[0]:
        raise SnnccError(f"{labels.shape[0]} labels for {x_all.shape[0]} samples", file=data, field="labels")
    mode = "stream" if options.stream else "batch"
    measured = measure(graph, bundle, x_all, mode=mode, gap=STREAM_GAP, progress=progress)
    c = measured.counts
    breakdown = bundle.lowered is not None
    stages = kit_stages(measured, labels, breakdown=breakdown)
    by_stage = {key: float(np.mean(measured.prediction(key) == labels)) for key in ("float_trained", *measured.stages)}
    quant = quantization_of(bundle)
    timing = bundle.network.metadata.get("timing")
    notes = [f"timing: {ch}" for ch in ((timing.get("changes") or []) if isinstance(timing, dict) else [])]
    notes += common_notes(bundle, measured)
    if synthetic:
        notes.append("the data set is synthetic: these accuracies are not the paper's")
    details = {"mode": mode, "timing": timing_mode(bundle), "scale_rule": str(quant.get("rule", "unknown")),
               "scale_reason": str(quant.get("reason", "not recorded")), "accuracy_by_stage": by_stage,
               "spike_agreement": measured.spike_agreement, "overflow": measured.overflow,
               "reset_changed": bundle.lowered is not None and bundle.lowered.deployed is not None}
    if measured.relayed:
        details["relayed_vs_emulator"] = argmax_agreement(c["emulator_without_relays"], c["emulator"]).as_dict()
    report = report_from(
        "loihi", inputs=f"{x_all.shape[0]} labelled samples" + (f" of {data}" if data else "")
        + (f" ({mode} mode)" if mode == "stream" else ""), samples=measured.samples, steps=measured.steps,
        artefact=argmax_agreement(c["float_trained"], c["emulator"]),
        count_correlation=count_correlation(c["emulator"], c["float_trained"]), stages=stages, possible=POSSIBLE,
        accuracy=accuracy_pair(measured.prediction("float_trained"), measured.prediction("emulator"), labels),
        notes=notes, details=details, detail_lines=detail_lines(details),
        **liveness_fields(graph, bundle, measured, x_all))
    if not breakdown:
        report.causes = {k: None for k in report.causes}
    return report


def detail_lines(details: dict) -> list[str]:
    """Loihi's own figures of a labelled check, as text."""
    out = [f"timing '{details['timing']}', scale '{details['scale_rule']}' ({details['mode']} mode): "
           f"{details['scale_reason']}",
           "accuracy by stage: " + ", ".join(f"{k} {100 * v:.2f} %" for k, v in details["accuracy_by_stage"].items())]
    for name, per_layer in details["spike_agreement"].items():
        out.append(f"spike agreement {name}: " + ", ".join(
            f"{k} {'undefined (silent)' if v is None else f'{100 * v:.2f}%'}" for k, v in per_layer.items()))
    out.append(f"overflow events: {details['overflow']}")
    return out
