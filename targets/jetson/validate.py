"""Validation of exported ONNX models, run after every export; any failure raises SnnccError.

1. ``onnx.checker`` (full check), no ``Sequence*`` / ``ConcatFromSequence`` (TensorRT has no
   sequence types) and no loop operators (``Loop``, ``Scan``, ``If``), every graph input used.
2. Every declared dynamic axis really is dynamic: each model is run at two sizes of it.
3. Against the IR reference (``snncc.ir.simulate``) in float32, the artefact's own precision, on
   seeded inputs: output spike agreement (>= 99.9 % required) or max |delta| of values (<= 1e-3 of
   their range), score delta, prediction agreement; the step model driven for T steps against the
   reference and against the sequence model. The float64 reference's agreement is measured beside
   and reported, not required: float32 against float64 is rounding (a long run of non-leaky neurons
   drifts by a spike where a voltage ties the threshold), which ``snncc check`` measures as loss, not
   an export bug.
4. fp16 emulation (weights, inputs and every arithmetic result rounded to float16, in torch):
   spike flips and score delta against the float32 ONNX result. Reported, not a failure: TensorRT --fp16 is the user's choice.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
import onnx
import onnxruntime as ort
import torch

from snncc.targets.kit import InternalError, SnnccError
from snncc.targets.kit.compute import one_thread
from snncc.ir.simulate import simulate
from snncc.targets.jetson.export import ExportedModel
from snncc.targets.jetson.plan import GraphPlan
from snncc.targets.jetson.torch_graph import fp16_step_model, round_fp16, run_steps

MIN_SPIKE_AGREEMENT = 0.999
VALUE_TOLERANCE = 1e-3          # relative to max(1, max |reference|)
BANNED_PREFIXES = ("Sequence", "ConcatFromSequence", "SplitToSequence")
BANNED_OPS = ("Loop", "Scan", "If")
MAIN_BATCH, SECOND_BATCH = 8, 3


@dataclass
class ValidationRecord:
    """What validation measured (stored in manifest.json under "validation")."""

    reference: str
    seed: int
    samples: int
    steps: int
    sequence: dict = field(default_factory=dict)
    step: dict = field(default_factory=dict)
    dynamic_axes_checked: list = field(default_factory=list)
    fp16: dict = field(default_factory=dict)
    passed: bool = True
    liveness: dict = field(default_factory=dict)   # every population on the validation inputs (float; the output on ONNX)

    def as_dict(self) -> dict:
        return asdict(self)


def _all_nodes(graph: onnx.GraphProto):
    for node in graph.node:
        yield node
        for attr in node.attribute:
            if attr.type == onnx.AttributeProto.GRAPH:
                yield from _all_nodes(attr.g)
            for sub in attr.graphs:
                yield from _all_nodes(sub)


def check_structure(model: ExportedModel, label: str) -> dict:
    """onnx.checker, banned operators, every input used. Returns the operator histogram."""
    proto = model.proto
    try:
        onnx.checker.check_model(proto, full_check=True)
    except Exception as ex:  # onnx raises several checker error types
        raise SnnccError(f"onnx.checker rejects the export: {str(ex).splitlines()[0]}", field=label) from None
    ops: dict[str, int] = {}
    consumed: set[str] = set()
    for node in _all_nodes(proto.graph):
        ops[node.op_type] = ops.get(node.op_type, 0) + 1
        consumed.update(node.input)
        if node.op_type.startswith(BANNED_PREFIXES) or node.op_type in BANNED_OPS:
            raise SnnccError(f"the export contains a {node.op_type} operator, which TensorRT does not support "
                             "(or is untested on a device)", field=label)
    outputs = {o.name for o in proto.graph.output}
    for inp in proto.graph.input:
        if inp.name not in consumed and inp.name not in outputs:
            raise SnnccError(f"graph input '{inp.name}' is not used by any operator", field=label)
    return dict(sorted(ops.items()))


def session(model: ExportedModel | bytes) -> ort.InferenceSession:
    data = model.data if isinstance(model, ExportedModel) else model
    opts = ort.SessionOptions()
    opts.log_severity_level = 3
    # the memory-reuse planner is quadratic in the number of values: minutes for an unrolled T = 270
    opts.enable_mem_reuse = False
    opts.intra_op_num_threads = 1
    return ort.InferenceSession(data, opts, providers=["CPUExecutionProvider"])


def seeded_inputs(plan: GraphPlan, batch: int, steps: int, seed: int) -> np.ndarray:
    """(batch, steps, base channels) float32: Bernoulli events at rates 5..40 % or N(0, 1) frames."""
    rng = np.random.default_rng(seed)
    if plan.signal == "spikes":
        rates = np.linspace(0.05, 0.4, batch)[:, None, None]
        return (rng.random((batch, steps, plan.base_inputs)) < rates).astype(np.float32)
    return rng.standard_normal((batch, steps, plan.base_inputs)).astype(np.float32)


def reference(plan: GraphPlan, x: np.ndarray, dtype=np.float32):
    """IR reference in ``dtype`` (float32: the artefact's precision) on base-channel data: copies tiled as the
    authors do."""
    tiled = np.tile(x, (1, 1, plan.input_copies)) if plan.input_copies > 1 else x
    res = simulate(plan.graph, tiled.astype(dtype), dtype=dtype)
    return np.asarray(res.output), (np.asarray(res.readout) if res.readout is not None else None)


def host_score(mode: str | None, seq: np.ndarray) -> np.ndarray:
    if mode == "membrane_max":
        return seq.max(axis=1)
    if mode == "last":
        return seq[:, -1]
    return seq.sum(axis=1)


def run_step_model(sess: ort.InferenceSession, x: np.ndarray) -> np.ndarray:
    """Drive step.onnx over x (B, T, C) from zero state; returns (B, T, n)."""
    ins = sess.get_inputs()
    states = {i.name: np.zeros((x.shape[0], *[int(d) for d in i.shape[1:]]), np.float32) for i in ins[1:]}
    out_names = [o.name for o in sess.get_outputs()]
    ys = []
    for t in range(x.shape[1]):
        res = sess.run(None, {ins[0].name: np.ascontiguousarray(x[:, t]), **states})
        ys.append(res[0])
        states = {i.name: r for i, r in zip(ins[1:], res[1:])}
    if out_names[0] != "y_t":
        raise InternalError(f"step.onnx's first output is {out_names[0]!r}, not 'y_t'", field="step.onnx")
    return np.stack(ys, axis=1)


def _compare(plan: GraphPlan, got_seq: np.ndarray | None, got_score: np.ndarray,
             ref_seq: np.ndarray, ref_score: np.ndarray, label: str) -> dict:
    """Agreement figures; raise if below the rule."""
    rec: dict = {}
    if got_seq is not None:
        if got_seq.shape != ref_seq.shape:
            raise InternalError(f"output has shape {got_seq.shape}, the reference {ref_seq.shape}", field=label)
        if plan.spiking_output:
            agree = float(np.mean(got_seq == ref_seq))
            rec["spike_agreement"] = agree
            rec["spikes_differing"] = int(np.sum(got_seq != ref_seq))
            if agree < MIN_SPIKE_AGREEMENT:
                raise InternalError(f"output spike agreement with the IR reference is {agree:.4%}, "
                                 f"below {MIN_SPIKE_AGREEMENT:.1%}", field=label)
        rec["max_abs_delta_outputs"] = float(np.max(np.abs(got_seq - ref_seq))) if got_seq.size else 0.0
    delta = float(np.max(np.abs(got_score - ref_score))) if got_score.size else 0.0
    rec["max_abs_delta_score"] = delta
    scale = max(1.0, float(np.max(np.abs(ref_score))) if ref_score.size else 1.0)
    if not plan.spiking_output and delta > VALUE_TOLERANCE * scale:
        raise InternalError(f"scores differ from the IR reference by {delta:.3g} (allowed {VALUE_TOLERANCE * scale:.3g})",
                         field=label)
    pred, ref_pred = np.argmax(got_score, axis=1), np.argmax(ref_score, axis=1)
    if plan.spiking_output and plan.score_mode in (None, "spike_count"):
        from snncc.targets.kit.agreement import argmax_agreement

        decisions = argmax_agreement(ref_score, got_score)   # silent or tied float outputs: left out, counted
        rec["prediction_agreement"] = decisions.share        # None: undefined (outputs silent)
        rec["prediction"] = decisions.as_dict()
    else:
        rec["prediction_agreement"] = float(np.mean(pred == ref_pred))
    if not plan.spiking_output:
        top2 = np.sort(ref_score, axis=1)[:, -2:] if ref_score.shape[1] > 1 else None
        clear = (top2[:, 1] - top2[:, 0] > 2 * delta) if top2 is not None else np.ones(len(pred), bool)
        if np.any((pred != ref_pred) & clear):
            raise InternalError("a prediction differs from the IR reference where the reference margin is clear",
                             field=label)
    return rec


REFERENCE = "snncc.ir.simulate in float32 (the artefact's precision); float64 agreement measured beside"


def float64_agreement(plan: GraphPlan, x: np.ndarray, got_seq: np.ndarray | None, got_score: np.ndarray) -> dict:
    """How model.onnx (float32) agrees with the float64 reference on the validation inputs: measured, not required."""
    seq64, score64 = reference(plan, x, np.float64)
    if score64 is None:
        score64 = host_score(plan.score_mode, seq64)
    rec: dict = {"max_abs_delta_score": float(np.max(np.abs(got_score - score64))) if got_score.size else 0.0}
    if got_seq is not None and plan.spiking_output and got_seq.shape == seq64.shape:
        rec["spike_agreement"] = float(np.mean(got_seq == seq64))
        rec["spikes_differing"] = int(np.sum(got_seq != seq64))
    rec["prediction_agreement"] = float(np.mean(np.argmax(got_score, 1) == np.argmax(score64, 1)))
    return rec


def _run_sequence(plan: GraphPlan, sess: ort.InferenceSession, x: np.ndarray):
    outs = sess.run(None, {sess.get_inputs()[0].name: x})
    score = outs[0]
    seq = outs[1] if len(outs) > 1 else None
    return seq, score


def validate_export(plan: GraphPlan, steps: int, sequence: ExportedModel, step: ExportedModel,
                    seed: int = 0) -> ValidationRecord:
    """Run every check; return the measured figures. An artefact that disagrees with the IR reference is
    a bug in the export (``InternalError``); an operator TensorRT lacks is the model's (``SnnccError``)."""
    with one_thread():
        return _validate(plan, steps, sequence, step, seed)


def _validate(plan: GraphPlan, steps: int, sequence: ExportedModel, step: ExportedModel, seed: int) -> ValidationRecord:
    record = ValidationRecord(reference=REFERENCE, seed=seed, samples=MAIN_BATCH, steps=steps)
    record.sequence["operators"] = check_structure(sequence, "model.onnx")
    record.step["operators"] = check_structure(step, "step.onnx")
    seq_sess, step_sess = session(sequence), session(step)

    x = seeded_inputs(plan, MAIN_BATCH, steps, seed)
    ref_seq, ref_score = reference(plan, x)
    if ref_score is None:
        ref_score = host_score(plan.score_mode, ref_seq)
    got_seq, got_score = _run_sequence(plan, seq_sess, x)
    record.sequence.update(_compare(plan, got_seq, got_score, ref_seq, ref_score, "model.onnx"))
    record.sequence["float64"] = float64_agreement(plan, x, got_seq, got_score)

    # a second shape on every dynamic axis: batch always; time too for whole-sequence models
    second_steps = steps if plan.has_lif else max(2, steps // 2 + 3)
    x2 = seeded_inputs(plan, SECOND_BATCH, second_steps, seed + 1)
    ref2_seq, ref2_score = reference(plan, x2)
    if ref2_score is None:
        ref2_score = host_score(plan.score_mode, ref2_seq)
    try:
        got2_seq, got2_score = _run_sequence(plan, seq_sess, x2)
    except Exception as ex:  # onnxruntime raises its own error types
        raise InternalError(f"a declared dynamic axis is not dynamic: shape {x2.shape} fails "
                         f"({type(ex).__name__})", field="model.onnx") from None
    second = _compare(plan, got2_seq, got2_score, ref2_seq, ref2_score, f"model.onnx (shape {x2.shape})")
    record.dynamic_axes_checked.append({"model": "model.onnx", "shapes": [list(x.shape), list(x2.shape)],
                                        "max_abs_delta_score": second["max_abs_delta_score"]})

    step_seq = run_step_model(step_sess, x)
    record.step.update(_compare(plan, step_seq, host_score(plan.score_mode, step_seq), ref_seq, ref_score, "step.onnx"))
    if got_seq is not None:
        if plan.spiking_output:
            agree = float(np.mean(step_seq == got_seq))
            record.step["agreement_with_sequence_model"] = agree
            if agree < MIN_SPIKE_AGREEMENT:
                raise InternalError(f"the step model driven for {steps} steps agrees with the sequence model on "
                                 f"only {agree:.4%} of output spikes", field="step.onnx")
        record.step["max_abs_delta_vs_sequence_model"] = float(np.max(np.abs(step_seq - got_seq)))
    else:
        record.step["max_abs_delta_vs_sequence_model"] = float(np.max(np.abs(step_seq[:, -1] - got_score)))
    try:
        step2 = run_step_model(step_sess, x2[:, : min(second_steps, 4)])
    except Exception as ex:
        raise InternalError(f"the batch axis is not dynamic: batch {SECOND_BATCH} fails ({type(ex).__name__})",
                         field="step.onnx") from None
    if not np.allclose(step2, ref2_seq[:, : step2.shape[1]], atol=VALUE_TOLERANCE * max(1.0, float(np.abs(ref2_seq).max()))):
        raise InternalError(f"batch {SECOND_BATCH} gives results that differ from the IR reference", field="step.onnx")
    record.dynamic_axes_checked.append({"model": "step.onnx", "shapes": [[MAIN_BATCH, plan.base_inputs],
                                                                         [SECOND_BATCH, plan.base_inputs]]})
    record.fp16 = fp16_emulation(plan, x, got_seq if got_seq is not None else step_seq, got_score)
    if plan.has_lif:
        record.liveness = validation_liveness(plan, x, got_seq)
    return record


def validation_liveness(plan: GraphPlan, x: np.ndarray, got_seq: np.ndarray | None) -> dict:
    """Every LIF population's activity on the validation inputs in float, the output population's on
    model.onnx, the silent or saturated ones named (compile's one-line warning for a model silent in float
    is ``snncc.ir.liveness.calibration_warning``)."""
    from snncc.ir import liveness
    from snncc.targets.jetson.populations import float_spikes, output_population

    refractory = liveness.graph_refractory(plan.graph)
    f_act = liveness.activity(float_spikes(plan, x), refractory)
    t_act = {}
    if got_seq is not None and plan.spiking_output:
        t_act = liveness.activity({output_population(plan): got_seq.astype(np.uint8)}, refractory)
    return {"inputs": f"the {x.shape[0]} seeded validation samples", "float": liveness.as_dicts(f_act),
            "jetson": liveness.as_dicts(t_act),
            "flagged": liveness.flagged(f_act, "in float") + liveness.flagged(t_act, "on the ONNX model")}


def fp16_run(plan: GraphPlan, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(outputs (B, T, n), score (B, n)) with weights and activations in float16 (torch step model)."""
    model = fp16_step_model(plan).eval()
    with torch.no_grad():
        seq16 = run_steps(model, round_fp16(torch.as_tensor(np.asarray(x, np.float32)))).numpy()
    return seq16, host_score(plan.score_mode, seq16)


FP16_METHOD = ("float16 weights, inputs and every arithmetic result (rounded; float32 accumulation inside "
               "matrix products) in the torch step model, vs float32 ONNX Runtime")


def fp16_emulation(plan: GraphPlan, x: np.ndarray, fp32_seq: np.ndarray, fp32_score: np.ndarray) -> dict:
    """Cast weights and activations to float16 (torch) and count what changes against float32."""
    seq16, score16 = fp16_run(plan, x)
    if fp32_seq.shape != seq16.shape:  # LIF-free models compare their scores only
        fp32_seq = None
    rec: dict = {"method": FP16_METHOD}
    if fp32_seq is not None and plan.spiking_output:
        rec["spike_flips"] = int(np.sum(seq16 != fp32_seq))
        rec["spike_flip_fraction"] = float(np.mean(seq16 != fp32_seq))
    elif fp32_seq is not None:
        rec["max_abs_delta_outputs"] = float(np.max(np.abs(seq16 - fp32_seq)))
    rec["max_abs_delta_score"] = float(np.max(np.abs(score16 - fp32_score)))
    rec["score_range"] = float(np.max(fp32_score) - np.min(fp32_score))
    rec["predictions_changed"] = int(np.sum(np.argmax(score16, 1) != np.argmax(fp32_score, 1)))
    return rec
