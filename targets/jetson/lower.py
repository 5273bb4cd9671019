"""Jetson's ``lower`` and ``check`` work: torch modules with the IR's exact semantics exported to ONNX
(whole sequence and streaming step) at the opset of the board's JetPack, validated in ONNX Runtime
against the IR reference (failing loudly); a ``JetsonArtefact`` whose ``write(dir)`` creates the
directory atomically:

    model.onnx  step.onnx  manifest.json  build_engine.sh  run.py

A buffered classifier (no IR graph) is lowered from its PyTorch module (``buffered.py``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.timebase import sample_steps
from snncc.targets.kit import Progress
from snncc.targets.jetson.check import check_artefact
from snncc.targets.jetson.options import DEFAULT_JETPACK, JetsonOptions
from snncc.targets.kit.artefact import model_record
from snncc.targets.kit.checks import CheckReport
from snncc.targets.jetson.export import export_sequence, export_step, opset_for_jetpack
from snncc.targets.jetson.manifest import ArtefactFiles, build_manifest, manifest_bytes
from snncc.targets.jetson.plan import GraphPlan, plan_graph
from snncc.targets.jetson.recipe import build_engine_script
from snncc.targets.jetson.validate import validate_export
from snncc.targets.kit.compute import one_thread

MAX_UNROLLED_STEPS = 5000
EXPORTING = "exporting the ONNX models"
VALIDATING = "validating in ONNX Runtime against the IR reference"


def runner_source() -> bytes:
    """run.py: the standalone runner module's own text (numpy + onnxruntime / tensorrt)."""
    return (Path(__file__).with_name("standalone_runner.py")).read_bytes()


def resolve_steps(plan: GraphPlan, options: JetsonOptions) -> tuple[int, str]:
    """(T for the export, the rule that gave it): --time-steps, else recording_length_s / dt, else the
    default every target uses for a model that states no recording length (``snncc.ir.timebase``)."""
    steps, rule = sample_steps(plan.graph, options.time_steps)
    if plan.has_lif and steps > MAX_UNROLLED_STEPS:
        raise SnnccError(f"{steps} steps is too long to unroll (max {MAX_UNROLLED_STEPS}); the step model "
                         "runs any length", field="--time-steps")
    return steps, rule


class JetsonArtefact(ArtefactFiles):
    """The artefact's files (bytes, in write order) and its manifest."""

    def summary(self) -> dict[str, Any]:
        v = self.manifest["validation"]
        return {
            **self.file_summary(),
            "validation": {
                "reference": v["reference"],
                "sequence": {k: x for k, x in v["sequence"].items() if k != "operators"},
                "step": {k: x for k, x in v["step"].items() if k != "operators"},
                "dynamic_axes_checked": v["dynamic_axes_checked"],
                "fp16": v["fp16"],
                "liveness": v.get("liveness", {}),
            },
            "notes": self.notes,
        }

    def render_text(self, console) -> None:
        from rich.table import Table

        m, v = self.manifest, self.manifest["validation"]
        console.print(f"[bold]Jetson artefact[/bold]  {m['model']['kind']} '{m['model']['name']}'   JetPack {m['jetpack']} "
                      f"-> ONNX opset {m['opset']} (TensorRT {m['tensorrt']})")
        table = Table(show_header=True)
        for col in ("file", "bytes", "interface"):
            table.add_column(col)
        for var in m["variants"]:
            sig = ", ".join(f"{t['name']}{tuple(t['shape'])}" for t in var["inputs"][:2])
            if len(var["inputs"]) > 2:
                sig += f", +{len(var['inputs']) - 2} state"
            outs = ", ".join(f"{t['name']}{tuple(t['shape'])}" for t in var["outputs"][:2])
            table.add_row(var["file"], f"{len(self.files[var['file']]):,}", f"{sig} -> {outs}")
        for name in ("manifest.json", "build_engine.sh", "run.py"):
            table.add_row(name, f"{len(self.files[name]):,}", "")
        console.print(table)
        inp = m["input"]
        console.print(f"input: {inp['channels']} channels x {m['time_steps']} steps (dt {m['dt']} s); "
                      f"{inp['note']}")
        seq, step, fp16 = v["sequence"], v["step"], v["fp16"]
        if "spike_agreement" in seq:
            from snncc.targets.kit.agreement import ArgmaxAgreement

            decided = (ArgmaxAgreement(**seq["prediction"]).text() if "prediction" in seq
                       else f"{seq['prediction_agreement']:.0%} equal")
            wide = seq.get("float64", {})
            beside = (f"; against float64: {wide['spike_agreement']:.4%} of output spikes (rounding, measured)"
                      if "spike_agreement" in wide else "")
            console.print(f"validated against the IR reference in float32 ({v['samples']} seeded samples): output "
                          f"spike agreement model.onnx {seq['spike_agreement']:.4%}, step.onnx "
                          f"{step['spike_agreement']:.4%}; predictions {decided}{beside}", markup=False)
        else:
            console.print(f"validated against the IR reference in float32 ({v['samples']} seeded samples): max |delta| score "
                          f"{seq['max_abs_delta_score']:.2g} (model.onnx), {step['max_abs_delta_score']:.2g} (step.onnx); "
                          f"predictions {seq['prediction_agreement']:.0%} equal")
        flips = f"{fp16['spike_flips']} spike flips, " if "spike_flips" in fp16 else ""
        console.print(f"fp16 emulation: {flips}max |delta| score {fp16['max_abs_delta_score']:.3g} "
                      f"(range {fp16['score_range']:.3g}), {fp16['predictions_changed']} predictions changed")
        for line in (v.get("liveness") or {}).get("flagged", []):
            console.print(f"liveness on the validation inputs: {line}", markup=False, style="yellow")
        for note in self.notes:
            console.print(f"note: {note}")


def lower_graph(graph: Graph, options: JetsonOptions, progress: Progress | None = None) -> JetsonArtefact:
    """The validated artefact of ``graph`` (options: jetpack, time_steps, seed, source);
    ``progress(done, total, phase)`` through the export and the validation."""
    plan = plan_graph(graph.copy())
    steps, steps_rule = resolve_steps(plan, options)
    jetpack = str(options.jetpack or DEFAULT_JETPACK)
    opset = opset_for_jetpack(jetpack)
    report = progress or (lambda done, total, phase: None)
    report(0, 2, EXPORTING)
    with one_thread():
        sequence = export_sequence(plan, steps, opset)
        report(1, 2, EXPORTING)
        step = export_step(plan, opset)
        report(2, 2, EXPORTING)
    report(0, 1, VALIDATING)
    record = validate_export(plan, steps, sequence, step, seed=int(options.seed))
    report(1, 1, VALIDATING)
    manifest = build_manifest(plan, steps, opset, jetpack, record.as_dict(), options.source, model_record(graph))
    files = {
        "model.onnx": sequence.data,
        "step.onnx": step.data,
        "manifest.json": manifest_bytes(manifest),
        "build_engine.sh": build_engine_script(manifest).encode("utf-8"),
        "run.py": runner_source(),
    }
    notes = ["validated in ONNX Runtime on this machine; TensorRT engines are built and run on the board"]
    if plan.has_lif:
        notes.append(f"model.onnx is unrolled for T = {steps} ({steps_rule}); step.onnx runs any length")
    else:
        notes.append(f"validated on T = {steps} ({steps_rule}); both models run any length")
    return JetsonArtefact(files, manifest, notes)


def check_graph(graph: Graph, inputs: np.ndarray, labels: np.ndarray | None, *, artefact: Path,
                data: str | None = None, synthetic: bool = False, progress=None) -> CheckReport:
    """The written artefact directory ``artefact`` against the IR reference on a data set
    (``check.check_artefact``: model.onnx, or step.onnx for data of another length); errors name ``data``."""
    from snncc.targets.jetson.written import WrittenJetson

    x = np.asarray(inputs)
    if x.ndim == 2:
        x = x[None]
    written = WrittenJetson.open(artefact)
    what = f"{x.shape[0]} labelled samples of {data or 'the data set'}" + (" (SYNTHETIC)" if synthetic else "")
    try:
        with one_thread():
            record = check_artefact(plan_graph(graph.copy()), written, x, labels, progress, inputs_text=what)
    except SnnccError as err:
        raise (err.with_file(data) if data is not None else err) from None
    if synthetic:
        record.notes.append("the data set is synthetic: these accuracies are not the paper's")
    return record


def agree_graph(graph: Graph, inputs: np.ndarray | None, *, artefact: Path, samples: int | None, density: float,
                noise: float | None = None, data: str | None = None, progress=None) -> CheckReport:
    """The written artefact's agreement with the float model without labels: on ``inputs``, or on
    ``samples`` (default ``kit.agreement.default_samples``) seeded random 0/1 trains of ``density`` as long
    as the artefact's T (SYNTHETIC); the float graph's own ceiling under ``noise`` weight noise."""
    from snncc.ir.nodes import LIF
    from snncc.targets.kit.agreement import default_samples, default_samples_note, random_inputs
    from snncc.targets.jetson.written import WrittenJetson

    written = WrittenJetson.open(artefact)
    plan = plan_graph(graph.copy())
    if inputs is None:
        n = samples or default_samples(sum(graph.node(p).n for p in graph.of_kind(LIF)), written.time_steps)
        x = random_inputs(n, written.time_steps, plan.base_inputs, density, seed=0)
        described = (f"{default_samples_note(n) if samples is None else f'{n} samples'}: seeded random 0/1 trains "
                     f"(density {density:g} per channel and step, seed 0), {written.time_steps} steps (SYNTHETIC)")
    else:
        x = np.asarray(inputs)
        described = f"{x.shape[0]} samples of {data or 'the given inputs'} (no labels used)"
    try:
        with one_thread():
            record = check_artefact(plan, written, x, None, progress, inputs_text=described, noise=noise)
    except SnnccError as err:
        raise (err.with_file(data) if data is not None else err) from None
    if inputs is None:
        record.notes.append("random inputs: agreement with the float model, not accuracy on real data")
    return record
