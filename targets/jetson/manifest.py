"""manifest.json: everything a runner on the board (or a person) needs to use the artefact.

Interface of every variant (names, shapes with "batch"/"time" for dynamic axes, dtypes), the
step model's state (input name -> output name, shape), time steps, dt, encoding, classes, the
input width as the data has it (copies applied inside the graph), opset, JetPack, source hash,
snncc version and the validation figures.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from snncc.targets.kit import SNNCC_VERSION
from snncc.targets.kit.inputs import frame_shape
from snncc.targets.kit.artefact import model_record
from snncc.targets.kit.manifest import source_identity
from snncc.targets.jetson.artefact_format import (  # noqa: F401 (the format's names, re-exported)
    EXECUTABLE, FORMAT, FORMAT_VERSION, JETSON_FORMAT, MANIFEST, WRITTEN_FILES, engines, listed_files)
from snncc.ir.nodes import LIF
from snncc.targets.jetson.plan import GraphPlan
from snncc.targets.jetson.recipe import TENSORRT_FOR_JETPACK



def _tensor(name: str, shape: list, dtype: str = "float32") -> dict:
    return {"name": name, "shape": shape, "dtype": dtype}


def model_kind(plan: GraphPlan) -> str:
    kind = plan.graph.metadata.get("model_kind")
    if kind:
        return str(kind)
    if not plan.has_lif:
        return "lstm"
    g = plan.graph
    recurrent = any(isinstance(g.node(u), LIF) and u in _downstream(g, u) for u in g.of_kind(LIF))
    return "rsnn" if recurrent else "ffsnn"


def _downstream(g, start: str) -> set[str]:
    seen: set[str] = set()
    todo = list(g.successors(start))
    while todo:
        n = todo.pop()
        if n in seen:
            continue
        seen.add(n)
        todo.extend(g.successors(n))
    return seen


def build_manifest(plan: GraphPlan, steps: int, opset: int, jetpack: str, validation: dict,
                   source: str | None, loaded: dict | None = None) -> dict:
    from snncc.targets.jetson.export import input_name, sequence_output_names   # torch: only when building
    from snncc.targets.jetson.torch_graph import state_slots

    g, meta = plan.graph, plan.graph.metadata
    x = input_name(plan)
    outs = sequence_output_names(plan)
    n_out = plan.output_width
    if plan.has_lif:
        seq_in = [_tensor(x, ["batch", steps, plan.base_inputs])]
        seq_out = [_tensor(outs[0], ["batch", n_out]), _tensor(outs[1], ["batch", steps, n_out])]
    else:
        seq_in = [_tensor(x, ["batch", "time", plan.base_inputs])]
        seq_out = [_tensor(outs[0], ["batch", n_out])]
    slots = state_slots(plan)
    step_in = [_tensor(f"{x}_t", ["batch", plan.base_inputs])] + [_tensor(s.input_name, ["batch", *s.shape]) for s in slots]
    step_out = [_tensor("y_t", ["batch", n_out])] + [_tensor(s.output_name, ["batch", *s.shape]) for s in slots]
    classes = meta.get("classes") or [str(i) for i in range(n_out)]
    frame = frame_shape(g)     # a CNN's input frame (C, H, W): runners flatten frames given in that shape
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "snncc_version": SNNCC_VERSION,
        "model": {"name": g.name, "kind": model_kind(plan), "update_order": meta.get("update_order")},
        "source": source_identity(meta, source),
        "loaded_model": loaded if loaded is not None else model_record(g),
        "jetpack": str(jetpack),
        "opset": opset,
        "tensorrt": TENSORRT_FOR_JETPACK.get(opset),
        "dt": g.dt,
        "time_steps": steps,
        "time_axis": "fixed (unrolled)" if plan.has_lif else "dynamic",
        "encoding": meta.get("encoding") or ("events (0/1)" if plan.signal == "spikes" else "analog frames"),
        "input": {"name": x, "channels": plan.base_inputs, "input_copies": plan.input_copies,
                  **({"frame_shape": frame} if frame else {}),
                  "graph_width": plan.base_inputs * plan.input_copies, "signal": plan.signal, "dtype": "float32",
                  "note": ("the model takes the channels as the data has them; the input copies are applied "
                           "inside the graph (concat of k copies on the channel axis)" if plan.input_copies > 1
                           else "no input copies")},
        "readout": {"mode": plan.score_mode, "score_output": outs[0],
                    "prediction": "argmax of the score over classes, ties to the lowest index (computed on the host)"},
        "classes": list(classes),
        "variants": [
            {"name": "sequence", "file": "model.onnx", "inputs": seq_in, "outputs": seq_out,
             "description": ("the whole sample, T fixed at export, unrolled" if plan.has_lif
                             else "the whole sample, native ONNX LSTM, dynamic batch and time")},
            {"name": "step", "file": "step.onnx", "inputs": step_in, "outputs": step_out,
             "description": "one time step, state in and out, the loop on the host (any T, streaming)",
             "state": [{"input": s.input_name, "output": s.output_name, "node": s.node, "what": s.what,
                        "shape": ["batch", *s.shape], "initial": 0.0} for s in slots]},
        ],
        "default_variant": "sequence",
        "validation": validation,
    }


def manifest_bytes(manifest: dict) -> bytes:
    return (json.dumps(manifest, indent=2, sort_keys=False) + "\n").encode("utf-8")


def write_artefact(path, files: dict[str, bytes]) -> None:
    """Write an artefact directory atomically, replacing only an earlier snncc Jetson artefact holding nothing
    but its own files and engines (``kit.manifest.ManifestFormat.write``)."""
    JETSON_FORMAT.write(path, files)


def own_names(manifest: Mapping[str, Any]) -> set[str]:
    """The names of an artefact's own files and the engines built beside them."""
    return set(listed_files(manifest)) | engines(manifest)


@dataclass
class ArtefactFiles:
    """A Jetson artefact: its files (bytes, in write order), manifest and notes; both artefact kinds
    (unrolled SNN/LSTM graphs, buffered classifiers) write and summarise their files this way."""

    files: dict[str, bytes]
    manifest: dict
    notes: list[str] = field(default_factory=list)

    def write(self, path: str | os.PathLike) -> None:
        write_artefact(path, self.files)

    def file_summary(self) -> dict[str, Any]:
        """The summary's fields both kinds share (model, file sizes and hashes, versions, interface)."""
        m = self.manifest
        return {
            "model": m["model"],
            "files": {n: {"bytes": len(d), "sha256": hashlib.sha256(d).hexdigest()} for n, d in self.files.items()},
            "jetpack": m["jetpack"], "opset": m["opset"], "tensorrt": m["tensorrt"],
            "time_steps": m["time_steps"], "time_axis": m["time_axis"], "dt": m["dt"],
            "input": m["input"],
            "variants": [{k: var[k] for k in ("name", "file", "inputs", "outputs")} for var in m["variants"]],
        }
