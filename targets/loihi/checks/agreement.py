"""Agreement of the written Loihi bundle with the float model, without labels (``snncc check`` without data).

For a graph that comes without a data set (a NIR export, say), what deployment loses is measured
against the float model itself, on user-supplied spike trains or on seeded random ones of a stated
density (each channel spikes with probability ``density`` per step, independently), as long as the
bundle's own sample (tSample less the outputs' shift). The record is the kit's ``CheckReport``:

    argmax agreement    share of decided samples whose emulated output-count argmax equals the float
                        one, with its count and 95 % interval (``kit.agreement``: samples whose float
                        output ties at the top or is silent are left out and counted)
    count correlation   Pearson correlation of all output spike counts (samples x classes), emulated vs float
    stages              the same stages as the labelled check (``stages.py``), so the loss is broken down by
                        cause: reset change, timing, weights, decays, saturation
    ceiling             the float model against itself with every trained weight multiplied by
                        (1 + noise * N(0, 1)), noise 0.01 by default (``kit.reference``): how sensitive the
                        model's decisions are to perturbations of that size on these inputs
    details             per layer: share of equal spike entries (undefined when both are silent) and the
                        correlation of per-neuron spike counts; the scale candidates' calibration errors;
                        overflow counts; the scale rule and why

The reference is the float model as trained, with its own reset. SYNTHETIC inputs (random spikes) say
nothing about accuracy on real data.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.base import AgreementOptions
from snncc.targets.kit import SnnccError
from snncc.targets.kit.checks import CheckReport

SEED = 0


def agree_bundle(graph: Graph, path: str | Path, inputs: np.ndarray | None, how: AgreementOptions, *,
                 data: str | None = None, progress: Callable[[int], None] | None = None) -> CheckReport:
    """Emulate the written bundle at ``path`` and compare it with ``graph``.

    ``inputs``: (N, T, C) 0/1 spikes; None draws ``how.samples`` seeded random spike trains of ``how.density``,
    the bundle's own length (default ``kit.agreement.default_samples``). ``progress(n)`` after each chunk."""
    from snncc.targets.kit.agreement import (argmax_agreement, count_correlation, default_samples,
                                             default_samples_note, random_inputs)
    from snncc.targets.kit.checks import ceiling_record, report_from
    from snncc.targets.kit.reference import float_counts, perturbed
    from snncc.targets.loihi.checks.stages import (POSSIBLE, common_notes, kit_stages, liveness_fields, measure,
                                                   quantization_of, timing_mode)
    from snncc.targets.loihi.checks.written import open_bundle
    from snncc.targets.loihi.emulation.emulator import check_inputs

    noise = float(how.noise)
    if not noise >= 0:
        raise SnnccError(f"weight noise must be >= 0, got {noise}", field="--noise")
    bundle = open_bundle(path, graph)
    net = bundle.network
    width = net.input_width
    if inputs is None:
        samples = how.samples
        if samples is None:
            samples = default_samples(sum(net.layers[bundle.layer_of[p]].model_n for p in bundle.populations),
                                      bundle.steps)
            said = default_samples_note(samples)
        else:
            said = f"{samples} samples"
        x_all = random_inputs(samples, bundle.steps, width, how.density, SEED)
        described = (f"{said}: seeded random spike trains (density {how.density:g} per channel and step, seed {SEED}), "
                     f"{bundle.steps} steps (SYNTHETIC)")
    else:
        x_all = check_inputs(inputs, width, source=data)
        described = f"{x_all.shape[0]} given spike trains of {x_all.shape[1]} steps"
    measured = measure(graph, bundle, x_all, progress=progress)
    c = measured.counts
    noisy = float_counts(perturbed(graph, noise), x_all, bundle.populations[-1])
    ceiling = argmax_agreement(c["float_trained"], noisy)
    breakdown = bundle.lowered is not None
    quant = quantization_of(bundle)
    live = liveness_fields(graph, bundle, measured, x_all)
    names = bundle.populations
    details = {
        "timing": timing_mode(bundle), "scale_rule": str(quant.get("rule", "unknown")),
        "scale_reason": str(quant.get("reason", "not recorded")),
        "layer_spike_agreement": measured.spike_agreement.get("emulator_vs_trained", {}),
        "layer_count_correlation": {k: count_correlation(measured.loihi_tally.of(k), measured.float_tally.of(k))
                                    for k in names},
        "ceiling_count_correlation": count_correlation(noisy, c["float_trained"]),
        "candidates": dict((quant.get("calibration") or {}).get("errors", {})), "overflow": measured.overflow,
        "spike_agreement": measured.spike_agreement}
    notes = []
    if inputs is None:
        notes.append("random spike trains: agreement with the float model, not accuracy on real data")
    notes += common_notes(bundle, measured)
    if breakdown and bundle.lowered.deployed is not None:
        notes.append("the bundle resets to zero where the model subtracts (--allow-reset-change): the reference is the "
                     "model as trained; stage (r) is the changed float model, so the cost of the change is a cause above")
    report = report_from(
        "loihi", inputs=described, samples=measured.samples, steps=measured.steps,
        artefact=argmax_agreement(c["float_trained"], c["emulator"]),
        count_correlation=count_correlation(c["emulator"], c["float_trained"]),
        stages=kit_stages(measured, breakdown=breakdown), possible=POSSIBLE,
        ceiling=ceiling_record(ceiling, noise), notes=notes, details=details, detail_lines=detail_lines(details),
        **live)
    if not breakdown:
        report.causes = {k: None for k in report.causes}
    return report


def detail_lines(details: dict) -> list[str]:
    """Loihi's own figures of an agreement check, as text."""
    def corr(v):
        return "undefined (constant counts)" if v is None else f"{v:.4f}"

    out = [f"scale rule '{details['scale_rule']}' (timing '{details['timing']}'): {details['scale_reason']}",
           f"ceiling count correlation {corr(details['ceiling_count_correlation'])}"]
    for name, a in details["layer_spike_agreement"].items():
        out.append(f"layer {name}: spike agreement " + ("undefined (silent)" if a is None else f"{100 * a:.2f} %")
                   + f", count correlation {corr(details['layer_count_correlation'].get(name))}")
    if details["candidates"]:
        out.append("scale candidates (calibration spike-count error): " + ", ".join(
            f"{k} {'undefined' if v is None else f'{v:.4f}'}" for k, v in details["candidates"].items()))
    if any(details["overflow"].values()):
        out.append(f"overflow events: {details['overflow']}")
    return out
