"""``snncc check --target jetson``: the IR reference against the ONNX Runtime artefact on a data set.

Reports accuracy of both (when labels are given), prediction agreement, output spike agreement
(SNNs), max |delta| of scores and outputs, and the fp16 emulation's spike flips and prediction
changes. The reference is ``snncc.ir.simulate`` in float64; the artefact runs in float32.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from snncc.errors import SnnccError
from snncc.targets.jetson.plan import GraphPlan
from snncc.targets.jetson.validate import FP16_METHOD, fp16_run, host_score, reference, session

BATCH = 64


@dataclass
class JetsonCheckRecord:
    target: str
    samples: int
    time_steps: int
    reference: str
    artefact: str
    accuracy_reference: float | None
    accuracy_artefact: float | None
    accuracy_fp16: float | None
    prediction_agreement: float
    spike_agreement: float | None
    max_abs_delta_score: float
    max_abs_delta_outputs: float | None
    fp16: dict
    validation: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)

    def render_text(self, console) -> None:
        def pct(v):
            return "n/a (no labels)" if v is None else f"{v:.2%}"

        console.print(f"[bold]snncc check --target jetson[/bold]  {self.samples} samples x {self.time_steps} steps")
        console.print(f"accuracy: IR reference {pct(self.accuracy_reference)}, ONNX Runtime artefact "
                      f"{pct(self.accuracy_artefact)}, fp16 emulation {pct(self.accuracy_fp16)}")
        console.print(f"prediction agreement (artefact vs reference): {self.prediction_agreement:.2%}")
        if self.spike_agreement is not None:
            console.print(f"output spike agreement: {self.spike_agreement:.4%}")
        console.print(f"max |delta| score: {self.max_abs_delta_score:.3g}" +
                      ("" if self.max_abs_delta_outputs is None else f"; outputs: {self.max_abs_delta_outputs:.3g}"))
        flips = f"{self.fp16['spike_flips']} spike flips, " if "spike_flips" in self.fp16 else ""
        console.print(f"fp16: {flips}{self.fp16['predictions_changed']} predictions changed, max |delta| score "
                      f"{self.fp16['max_abs_delta_score']:.3g}")
        for note in self.notes:
            console.print(f"note: {note}")


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


def check_artefact(plan: GraphPlan, artefact, inputs: np.ndarray, labels: np.ndarray | None,
                   progress=None) -> JetsonCheckRecord:
    """``progress(n)`` (optional) is called with the number of samples done after each batch."""
    x = _base_channels(plan, np.asarray(inputs, dtype=np.float32))
    if labels is not None and len(labels) != x.shape[0]:
        raise SnnccError(f"{len(labels)} labels for {x.shape[0]} samples", field="labels")
    manifest = artefact.manifest
    if manifest["time_axis"] != "dynamic" and x.shape[1] != manifest["time_steps"]:
        raise SnnccError(f"data have {x.shape[1]} time steps, the artefact {manifest['time_steps']}", field="inputs")
    sess = session(artefact.files["model.onnx"])
    in_name = sess.get_inputs()[0].name
    ref_seq, ref_score, got_seq, got_score = [], [], [], []
    for start in range(0, x.shape[0], BATCH):
        xb = x[start:start + BATCH]
        rs, rsc = reference(plan, xb)
        ref_seq.append(rs)
        ref_score.append(rsc if rsc is not None else host_score(plan.score_mode, rs))
        outs = sess.run(None, {in_name: xb})
        got_score.append(outs[0])
        if len(outs) > 1:
            got_seq.append(outs[1])
        if progress is not None:
            progress(len(xb))
    ref_seq_a, ref_score_a = np.concatenate(ref_seq), np.concatenate(ref_score)
    got_score_a = np.concatenate(got_score)
    got_seq_a = np.concatenate(got_seq) if got_seq else None
    pred, ref_pred = np.argmax(got_score_a, 1), np.argmax(ref_score_a, 1)
    seq16, score16 = [], []
    for start in range(0, x.shape[0], BATCH):
        a, b = fp16_run(plan, x[start:start + BATCH])
        seq16.append(a)
        score16.append(b)
    seq16_a, score16_a = np.concatenate(seq16), np.concatenate(score16)
    pred16 = np.argmax(score16_a, 1)
    fp16 = {"method": FP16_METHOD, "predictions_changed": int(np.sum(pred16 != pred)),
            "max_abs_delta_score": float(np.max(np.abs(score16_a - got_score_a)))}
    if got_seq_a is not None and plan.spiking_output:
        fp16["spike_flips"] = int(np.sum(seq16_a != got_seq_a))
        fp16["spike_flip_fraction"] = float(np.mean(seq16_a != got_seq_a))
    def acc(p):
        return None if labels is None else float(np.mean(p == np.asarray(labels)))

    notes = ["reference: snncc.ir.simulate float64; artefact: model.onnx in ONNX Runtime float32 (CPU)"]
    return JetsonCheckRecord(
        target="jetson", samples=int(x.shape[0]), time_steps=int(x.shape[1]),
        reference="snncc.ir.simulate (float64)", artefact="model.onnx, ONNX Runtime (float32)",
        accuracy_reference=acc(ref_pred), accuracy_artefact=acc(pred), accuracy_fp16=acc(pred16),
        prediction_agreement=float(np.mean(pred == ref_pred)),
        spike_agreement=float(np.mean(got_seq_a == ref_seq_a)) if (got_seq_a is not None and plan.spiking_output) else None,
        max_abs_delta_score=float(np.max(np.abs(got_score_a - ref_score_a))),
        max_abs_delta_outputs=float(np.max(np.abs(got_seq_a - ref_seq_a))) if got_seq_a is not None else None,
        fp16=fp16, validation=artefact.manifest["validation"], notes=notes,
    )
