"""Jetson artefacts of the buffered classifiers (FCN, ResNet, Encoder, Time-CNN, Inception).

These networks have no IR graph: the IR's networks advance one time step at a time (its Conv is
a convolution over a spatial map within one step), while these classifiers convolve over the time
axis of the whole buffered sample, with batch normalisation, residual sums and global pooling. So
their reference is the PyTorch module of the checkpoint itself: ``model.onnx`` (legacy exporter,
the JetPack's opset, dynamic batch, T fixed: the whole buffered sample) must pass ``onnx.checker``
and the TensorRT operator rules, run at two batch sizes, and agree with PyTorch in ONNX Runtime on
seeded N(0, 1) frames: max |delta score| <= 1e-3 x max(1, max |score|) and the same predictions,
else SnnccError.
There is no step model: a buffered classifier needs the whole sample before it can answer.

Files: model.onnx, manifest.json (the same format the runner and ``snncc bench`` read),
build_engine.sh, run.py. The model record (PyTorch module, metadata, source) comes from the frontend
(``snncc.frontends.buffered``) through ``lower``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from snncc.targets.jetson.options import DEFAULT_JETPACK, JetsonOptions
from snncc.targets.kit import SNNCC_VERSION, InternalError, SnnccError
from snncc.targets.jetson.export import _export, opset_for_jetpack
from snncc.targets.jetson.manifest import FORMAT, FORMAT_VERSION, ArtefactFiles, manifest_bytes
from snncc.targets.jetson.recipe import TENSORRT_FOR_JETPACK, build_engine_script
from snncc.targets.jetson.validate import VALUE_TOLERANCE, check_structure, session
from snncc.targets.kit.compute import one_thread

if TYPE_CHECKING:
    from snncc.targets.kit.models import BufferedModel
    from snncc.targets.kit.models import BufferedClassifier

MAIN_BATCH, SECOND_BATCH = 8, 3


def seeded_frames(batch: int, steps: int, channels: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal((batch, steps, channels)).astype(np.float32)


def validate_buffered(module: BufferedClassifier, data: bytes, seed: int = 0) -> dict:
    """model.onnx vs the PyTorch module (float32) in ONNX Runtime; raises SnnccError on disagreement."""
    from snncc.targets.jetson.export import ExportedModel

    cfg = module.config
    ops = check_structure(ExportedModel(data, ["frames"], ["scores"], {}), "model.onnx")
    sess = session(data)
    record: dict[str, Any] = {"reference": "the checkpoint's PyTorch module (float32; a buffered classifier has no IR graph)",
                              "seed": seed, "operators": ops}
    worst, agree, total = 0.0, 0, 0
    for batch, s in ((MAIN_BATCH, seed), (SECOND_BATCH, seed + 1)):
        x = seeded_frames(batch, cfg.n_steps, cfg.n_inputs, s)
        with torch.no_grad():
            ref = module.eval()(torch.from_numpy(x)).numpy()
        got = sess.run(None, {"frames": x})[0]
        if got.shape != ref.shape:
            raise InternalError(f"model.onnx gives scores of shape {got.shape} at batch {batch}, PyTorch {ref.shape}",
                             field="model.onnx")
        delta = float(np.max(np.abs(got - ref)))
        scale = max(1.0, float(np.max(np.abs(ref))))
        if not delta <= VALUE_TOLERANCE * scale:
            raise InternalError(f"model.onnx disagrees with PyTorch: max |delta score| {delta:.3g} at batch {batch} "
                             f"(tolerance {VALUE_TOLERANCE * scale:.3g})", field="model.onnx")
        worst = max(worst, delta)
        agree += int(np.sum(np.argmax(got, 1) == np.argmax(ref, 1)))
        total += batch
    record.update({"samples": total, "batch_sizes_checked": [MAIN_BATCH, SECOND_BATCH],
                   "max_abs_delta_score": worst, "prediction_agreement": agree / total})
    if agree != total:
        raise InternalError(f"model.onnx changes {total - agree} of {total} predictions against PyTorch",
                         field="model.onnx")
    return record


def build_buffered_manifest(module: BufferedClassifier, meta: dict, opset: int, jetpack: str, validation: dict,
                            source: str | None, source_sha256: str | None) -> dict:
    cfg = module.config
    classes = meta.get("classes") or [str(i) for i in range(cfg.n_outputs)]
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "snncc_version": SNNCC_VERSION,
        "model": {"name": cfg.kind, "kind": cfg.kind, "update_order": None},
        "source": {"file": source, "sha256": source_sha256},
        "jetpack": str(jetpack),
        "opset": opset,
        "tensorrt": TENSORRT_FOR_JETPACK.get(opset),
        "dt": cfg.dt,
        "time_steps": cfg.n_steps,
        "time_axis": "fixed (buffered: the whole sample)",
        "encoding": meta.get("encoding") or "analog frames",
        "input": {"name": "frames", "channels": cfg.n_inputs, "input_copies": 1, "graph_width": cfg.n_inputs,
                  "signal": "analog", "dtype": "float32", "note": "the whole sample of frames, buffered"},
        "readout": {"mode": "scores", "score_output": "scores",
                    "prediction": "argmax of the score over classes, ties to the lowest index (computed on the host)"},
        "classes": list(classes),
        "variants": [{"name": "sequence", "file": "model.onnx",
                      "inputs": [{"name": "frames", "shape": ["batch", cfg.n_steps, cfg.n_inputs], "dtype": "float32"}],
                      "outputs": [{"name": "scores", "shape": ["batch", cfg.n_outputs], "dtype": "float32"}],
                      "description": "the whole buffered sample, T fixed, dynamic batch (no step model)"}],
        "default_variant": "sequence",
        "validation": validation,
    }


class BufferedArtefact(ArtefactFiles):
    """A buffered classifier's artefact (model.onnx only: no step model)."""

    def summary(self) -> dict[str, Any]:
        return {**self.file_summary(),
                "validation": {k: v for k, v in self.manifest["validation"].items() if k != "operators"},
                "notes": self.notes}

    def render_text(self, console) -> None:
        m, v = self.manifest, self.manifest["validation"]
        console.print(f"[bold]Jetson artefact[/bold]  {m['model']['kind']} (buffered classifier)   JetPack {m['jetpack']} "
                      f"-> ONNX opset {m['opset']} (TensorRT {m['tensorrt']})")
        for name, data in self.files.items():
            console.print(f"  {name}: {len(data):,} bytes")
        console.print(f"input: frames (batch, {m['time_steps']}, {m['input']['channels']}) -> scores "
                      f"(batch, {len(m['classes'])})")
        console.print(f"validated against PyTorch in ONNX Runtime ({v['samples']} seeded samples, batches "
                      f"{v['batch_sizes_checked']}): max |delta score| {v['max_abs_delta_score']:.2g}; predictions "
                      f"{v['prediction_agreement']:.0%} equal")
        for note in self.notes:
            console.print(f"note: {note}")


def lower_buffered(model: BufferedModel, options: JetsonOptions | None = None, progress=None) -> BufferedArtefact:
    """A validated Jetson artefact of a buffered classifier (``snncc.frontends.buffered.BufferedModel``;
    options: jetpack, seed, time_steps); ``progress(done, total, phase)`` through export and validation."""
    from snncc.targets.jetson.lower import EXPORTING, VALIDATING, runner_source

    module, meta = model.module, dict(model.metadata)
    options = options or JetsonOptions()
    report = progress or (lambda done, total, phase: None)
    given = options.time_steps
    if given is not None and int(given) != module.config.n_steps:
        raise SnnccError(f"a buffered {module.config.kind} takes exactly {module.config.n_steps} frames "
                         f"(its architecture), not {given}", field="--time-steps")
    jetpack = str(options.jetpack or DEFAULT_JETPACK)
    opset = opset_for_jetpack(jetpack)
    module = module.eval()
    with one_thread():
        report(0, 1, EXPORTING)
        example = torch.from_numpy(seeded_frames(2, module.config.n_steps, module.config.n_inputs, 7))
        exported = _export(module, (example,), ["frames"], ["scores"], {"frames": {0: "batch"}, "scores": {0: "batch"}},
                           opset)
        report(1, 1, EXPORTING)
        report(0, 1, VALIDATING)
        validation = validate_buffered(module, exported.data, seed=int(options.seed))
        report(1, 1, VALIDATING)
    manifest = build_buffered_manifest(module, meta, opset, jetpack, validation, model.source_file,
                                       model.source_sha256)
    files = {"model.onnx": exported.data, "manifest.json": manifest_bytes(manifest),
             "build_engine.sh": build_engine_script(manifest).encode("utf-8"), "run.py": runner_source()}
    notes = ["validated in ONNX Runtime against the PyTorch module on this machine; TensorRT engines are built "
             "and run on the board",
             "buffered classifier: one variant (model.onnx), no streaming step model; fp16 not emulated"]
    return BufferedArtefact(files, manifest, notes)
