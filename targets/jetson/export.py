"""ONNX export with torch's legacy (TorchScript) exporter, which is exact for these models.

Why not dynamo (torch 2.13, measured): it bakes T into graphs that claim a dynamic time axis,
re-exports ``nn.LSTM`` with a static T, and merges example inputs built as one reused tensor.
The opset follows the board's JetPack (its TensorRT's ONNX parser): 4.6.x -> 13 (TensorRT 8.2,
the paper's board, the default), 5.x / 6.0 -> 17 (TensorRT 8.5 / 8.6), 6.1+ -> 20 (TensorRT 10.3).
Every model is one self-contained file (weights inline), byte-identical for identical input.
"""

from __future__ import annotations

import io
import re
import warnings
from dataclasses import dataclass

import onnx
import torch

from snncc.targets.kit import SnnccError
from snncc.targets.jetson.plan import GraphPlan
from snncc.targets.jetson.torch_graph import StepModel, UnrolledModel, WholeSequenceModel

DEFAULT_JETPACK = "4.6"
# JetPack releases with a TensorRT this target knows the ONNX opset of (x.y; any x.y.z patch release)
KNOWN_JETPACKS = ((4, 6), (5, 0), (5, 1), (6, 0), (6, 1), (6, 2))


def opset_for_jetpack(jetpack: str | None) -> int:
    """JetPack version string -> the highest ONNX opset its TensorRT parses."""
    text = str(jetpack or DEFAULT_JETPACK).strip()
    m = re.fullmatch(r"(\d+)(?:\.(\d+))?(?:\.\d+)*", text)
    if not m:
        raise SnnccError(f"not a JetPack version (expected e.g. 4.6, 5.1.2, 6.1), got {text!r}", field="--jetpack")
    major, minor = int(m.group(1)), int(m.group(2) or 0)
    if (major, minor) not in KNOWN_JETPACKS and (major, minor) >= (4, 6):
        known = ", ".join(f"{a}.{b}" for a, b in KNOWN_JETPACKS)
        raise SnnccError(f"unknown JetPack version {text} (this snncc knows {known}, patch releases included)",
                         field="--jetpack")
    if major == 4 and minor >= 6:
        return 13
    if major == 5 or (major == 6 and minor == 0):
        return 17
    if major >= 6:
        return 20
    raise SnnccError(f"JetPack {text} is older than 4.6 (TensorRT 8.2), the oldest this target supports",
                     field="--jetpack")


@dataclass
class ExportedModel:
    """An exported ONNX model and its interface."""

    data: bytes
    inputs: list[str]
    outputs: list[str]
    dynamic_axes: dict[str, dict[int, str]]

    @property
    def proto(self) -> onnx.ModelProto:
        return onnx.load_from_string(self.data)


def _export(module: torch.nn.Module, args: tuple, inputs: list[str], outputs: list[str],
            dynamic_axes: dict[str, dict[int, str]], opset: int) -> ExportedModel:
    module.eval()
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with torch.no_grad():
            torch.onnx.export(module, args, buf, dynamo=False, opset_version=opset, input_names=inputs,
                              output_names=outputs, dynamic_axes=dynamic_axes, do_constant_folding=True,
                              export_params=True)
    model = onnx.load_from_string(buf.getvalue())
    model.producer_name = "snncc (torch legacy ONNX exporter)"
    model.doc_string = ""
    return ExportedModel(model.SerializeToString(deterministic=True), inputs, outputs, dynamic_axes)


def input_name(plan: GraphPlan) -> str:
    return "events" if plan.signal == "spikes" else "frames"


def sequence_output_names(plan: GraphPlan) -> list[str]:
    if not plan.has_lif:
        return ["scores"]
    return ["counts", "output_spikes"] if plan.spiking_output and plan.score_mode == "spike_count" else ["scores", "output_values"]


def export_sequence(plan: GraphPlan, steps: int, opset: int) -> ExportedModel:
    """model.onnx: the whole sample. SNNs: T fixed, unrolled; LIF-free graphs: dynamic T."""
    name = input_name(plan)
    outputs = sequence_output_names(plan)
    # distinct example tensors with distinct sizes per axis (batch 2, so batch is never confused with 1)
    example = (torch.rand(2, steps, plan.base_inputs, generator=torch.Generator().manual_seed(0)) < 0.5).float()
    if plan.has_lif:
        module = UnrolledModel(plan, steps)
        axes = {name: {0: "batch"}, **{o: {0: "batch"} for o in outputs}}
    else:
        module = WholeSequenceModel(plan)
        axes = {name: {0: "batch", 1: "time"}, outputs[0]: {0: "batch"}}
    return _export(module, (example,), [name], outputs, axes, opset)


def export_step(plan: GraphPlan, opset: int) -> ExportedModel:
    """step.onnx: one step; state in, state out; the host runs the loop (any T, streaming)."""
    module = StepModel(plan)
    x_name = f"{input_name(plan)}_t"
    ins = [x_name] + [s.input_name for s in module.slots]
    outs = ["y_t"] + [s.output_name for s in module.slots]
    example = (torch.rand(2, plan.base_inputs, generator=torch.Generator().manual_seed(1)) < 0.5).float()
    states = tuple(module.initial_state(2))  # one fresh tensor per state
    axes = {n: {0: "batch"} for n in ins + outs}
    return _export(module, (example, *states), ins, outs, axes, opset)
