"""``snncc check --target jetson``: the IR reference against the written artefact (``kit.checks.CheckReport``).

The artefact is run from its directory (``written.py``: ``model.onnx`` in ONNX Runtime, or
``step.onnx`` step by step for inputs of another length). Reports accuracy of both (when labels
are given), prediction agreement (``snncc.measure.agreement``: samples whose float output ties at
the top or is silent are left out and counted), output spike agreement (SNNs), max |delta| of
scores and outputs, the fp16 emulation's spike flips and prediction changes, and every
population's liveness (in float; on the artefact: its output population, the one the ONNX model
exposes). The reference is ``snncc.ir.simulate`` in float64; the artefact runs in float32, the one cause of
loss that can occur on it ("other": float32 arithmetic; the fp16 emulation is shown beside, not a stage).
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.jetson.plan import GraphPlan
from snncc.targets.jetson.populations import float_spikes, output_population
from snncc.targets.jetson.validate import FP16_METHOD, fp16_run, host_score, reference
from snncc.targets.kit.checks import CheckReport

BATCH = 64


def _base_channels(plan: GraphPlan, x: np.ndarray) -> np.ndarray:
    c = x.shape[2]
    if c == plan.base_inputs:
        return x
    k = plan.input_copies
    if k > 1 and c == plan.base_inputs * k:
        copies = np.split(x, k, axis=2)
        if all(np.array_equal(copies[0], other) for other in copies[1:]):
            return copies[0]
    raise SnnccError(f"data have {c} channels, the model takes {plan.base_inputs}", field="inputs")


def check_artefact(plan: GraphPlan, written, inputs: np.ndarray, labels: np.ndarray | None,
                   progress=None, *, inputs_text: str = "the given inputs", noise: float | None = None) -> CheckReport:
    """The written artefact (``written.WrittenJetson``) against the IR reference on ``inputs``;
    ``progress(n)`` (optional) is called with the number of samples done after each batch."""
    from snncc.ir import liveness
    from snncc.targets.kit.agreement import argmax_agreement, count_correlation
    from snncc.targets.kit.checks import ceiling_record, report_from, stage
    from snncc.targets.kit.reference import noise_ceiling

    x = _base_channels(plan, np.asarray(inputs, dtype=np.float32))
    if labels is not None and len(labels) != x.shape[0]:
        raise SnnccError(f"{len(labels)} labels for {x.shape[0]} samples", field="labels")
    from snncc.ir.nodes import LIF
    from snncc.targets.kit.agreement import chunk_size

    batch = chunk_size(sum(plan.graph.node(p).n for p in plan.graph.of_kind(LIF)), x.shape[1], BATCH)
    ref_seq, ref_score, got_seq, got_score = [], [], [], []
    float_tally, target_tally = liveness.Tally(), liveness.Tally()
    for start in range(0, x.shape[0], batch):
        xb = x[start:start + batch]
        rs, rsc = reference(plan, xb)
        ref_seq.append(rs)
        ref_score.append(rsc if rsc is not None else host_score(plan.score_mode, rs))
        if plan.has_lif:
            float_tally.add(float_spikes(plan, xb))
        score, seq = written.run(xb)
        got_score.append(score)
        if seq is not None:
            got_seq.append(seq)
            if plan.spiking_output:
                target_tally.add({output_population(plan): seq.astype(np.uint8)})
        if progress is not None:
            progress(len(xb))
    ref_seq_a, ref_score_a = np.concatenate(ref_seq), np.concatenate(ref_score)
    got_score_a = np.concatenate(got_score)
    got_seq_a = np.concatenate(got_seq) if got_seq else None
    pred = np.argmax(got_score_a, 1)
    seq16, score16 = [], []
    for start in range(0, x.shape[0], batch):
        a, b = fp16_run(plan, x[start:start + batch])
        seq16.append(a)
        score16.append(b)
    seq16_a, score16_a = np.concatenate(seq16), np.concatenate(score16)
    pred16 = np.argmax(score16_a, 1)
    fp16 = {"method": FP16_METHOD, "predictions_changed": int(np.sum(pred16 != pred)),
            "max_abs_delta_score": float(np.max(np.abs(score16_a - got_score_a)))}
    if got_seq_a is not None and plan.spiking_output and seq16_a.shape == got_seq_a.shape:
        fp16["spike_flips"] = int(np.sum(seq16_a != got_seq_a))
        fp16["spike_flip_fraction"] = float(np.mean(seq16_a != got_seq_a))

    def acc(p):
        return None if labels is None else float(np.mean(p == np.asarray(labels)))

    spiking = bool(plan.spiking_output and plan.score_mode in (None, "spike_count"))
    agreement = argmax_agreement(ref_score_a, got_score_a, spiking=spiking)
    f_act = float_tally.activity(liveness.graph_refractory(plan.graph)) if plan.has_lif else {}
    t_act = target_tally.activity(liveness.graph_refractory(plan.graph)) if target_tally.counts else {}
    warning = None
    if f_act:
        tiled = np.tile(x[:batch], (1, 1, plan.input_copies)) if plan.input_copies > 1 else x[:batch]
        warning = liveness.float_silence_warning(plan.graph, tiled.astype(np.float64), f_act, "these inputs")
    notes = ["reference: snncc.ir.simulate float64; artefact: the written "
             f"{written.variants_ran()} in ONNX Runtime float32 (CPU)"]
    if "step.onnx" in written.ran:
        notes.append(f"the data have {x.shape[1]} steps and model.onnx is unrolled for {written.time_steps}: the step "
                     "model ran them one step at a time")
    ceiling = None
    if noise is not None and noise > 0 and spiking and plan.has_lif:
        ceiling = ceiling_record(noise_ceiling(plan.graph, _tiled(plan, x), ref_score_a.astype(np.int64), noise), noise)
    spike_agreement = (float(np.mean(got_seq_a == ref_seq_a)) if (got_seq_a is not None and plan.spiking_output)
                       else None)
    details = {"runtime": f"{written.variants_ran()}, ONNX Runtime (float32)", "reference_precision": "float64",
               "spike_agreement": spike_agreement,
               "max_abs_delta_score": float(np.max(np.abs(got_score_a - ref_score_a))),
               "max_abs_delta_outputs": float(np.max(np.abs(got_seq_a - ref_seq_a))) if got_seq_a is not None else None,
               "fp16": {**fp16, "accuracy": acc(pred16)}, "validation": written.manifest["validation"]}
    lines = [f"runs: {details['runtime']}; reference float64"]
    if spike_agreement is not None:
        lines.append(f"output spike agreement: {spike_agreement:.4%}")
    lines.append(f"max |delta| score: {details['max_abs_delta_score']:.3g}" + (
        "" if details["max_abs_delta_outputs"] is None else f"; outputs: {details['max_abs_delta_outputs']:.3g}"))
    flips = f"{fp16['spike_flips']} spike flips, " if "spike_flips" in fp16 else ""
    lines.append(f"fp16 (TensorRT --fp16, emulated): {flips}{fp16['predictions_changed']} predictions changed, max "
                 f"|delta| score {fp16['max_abs_delta_score']:.3g}" + (
                     "" if labels is None else f", accuracy {100 * acc(pred16):.2f} %"))
    stages = [stage("artefact", f"the written {written.variants_ran()} in ONNX Runtime, float32", "other", agreement,
                    acc(pred))]
    return report_from(
        "jetson", inputs=inputs_text, samples=int(x.shape[0]), steps=int(x.shape[1]), artefact=agreement,
        count_correlation=count_correlation(got_score_a, ref_score_a), stages=stages, possible=("other",),
        accuracy=None if labels is None else {"float": acc(np.argmax(ref_score_a, 1)), "artefact": acc(pred)},
        ceiling=ceiling, liveness={"float": liveness.as_dicts(f_act), "jetson": liveness.as_dicts(t_act)},
        flagged=liveness.flagged(f_act, "in float") + liveness.flagged(t_act, "on the Jetson artefact"),
        warnings=[warning] if warning else [], notes=notes, details=details, detail_lines=lines)


def _tiled(plan: GraphPlan, x: np.ndarray) -> np.ndarray:
    """``x`` with the graph's input copies applied (what the IR graph takes)."""
    return np.tile(x, (1, 1, plan.input_copies)) if plan.input_copies > 1 else x
