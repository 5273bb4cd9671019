#!/usr/bin/env python3
"""Run an snncc Jetson artefact: TensorRT where importable (and an engine was built), else ONNX Runtime.

This file is also copied into every artefact as ``run.py``: it needs only numpy and onnxruntime
(or tensorrt + pycuda on the board), never snncc.

    python3 run.py --input x.npy [--stream] [-o out.npz] [--backend auto|tensorrt|onnxruntime]

``x.npy``: (T, C) or (B, T, C) with C = manifest["input"]["channels"] (the data's own channels;
input copies are applied inside the model), or a CNN's frames (B, T, *manifest["input"]["frame_shape"]).
Output: for SNNs ``output_spikes`` (B, T, n) uint8,
``counts`` (B, n), ``prediction`` (B,); for LSTMs ``scores`` (B, n) and ``prediction``.
``--stream`` feeds step.onnx one time step at a time (any T), the state kept on the host.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np


class RunnerError(ValueError):
    """Bad input to the runner: ``field`` names what is wrong, the message the rule."""

    def __init__(self, rule: str, field: str):
        self.rule, self.field = rule, field
        super().__init__(f"{field}: {rule}")


def load_manifest(directory: str) -> dict:
    path = os.path.join(directory, "manifest.json")
    if not os.path.isfile(path):
        raise RunnerError("not a Jetson artefact directory (no manifest.json)", field=str(directory))
    try:
        with open(path, encoding="utf-8") as f:
            manifest = json.load(f)
    except (OSError, ValueError) as ex:
        raise RunnerError(f"manifest.json cannot be read ({type(ex).__name__})", field=path) from None
    if not isinstance(manifest, dict) or manifest.get("format") != "snncc-jetson-artefact":
        raise RunnerError("manifest.json is not an snncc Jetson manifest (field 'format')", field=path)
    variants = manifest.get("variants")
    if not isinstance(variants, list) or not all(isinstance(v, dict) for v in variants):
        raise RunnerError("must be a list of objects", field="manifest.json/variants")
    for i, v in enumerate(variants):
        artefact_file(directory, v.get("file"), f"manifest.json/variants/{i}/file")
    return manifest


def artefact_file(directory: str, name, field: str) -> str:
    """The path of a file the manifest names, which must lie inside the artefact directory: a
    relative name without '..' whose real path (after symlinks) is under the directory's."""
    parts = name.replace("\\", "/").split("/") if isinstance(name, str) else []
    if not parts or not name or os.path.isabs(name) or ".." in parts:
        raise RunnerError(f"{name!r} is not a file name inside the artefact (no absolute path, no '..')",
                          field=field)
    root = os.path.realpath(directory)
    if os.path.commonpath([root, os.path.realpath(os.path.join(root, name))]) != root:
        raise RunnerError(f"{name!r} leads outside the artefact (through a symlink)", field=field)
    return os.path.join(directory, name)


def _variant(manifest: dict, name: str) -> dict:
    for v in manifest["variants"]:
        if v.get("name") == name:
            return v
    raise RunnerError(f"the artefact has no {name} variant", field="manifest.json")


# ---- backends: a session runs one model file; run(feeds: dict) -> list of outputs in manifest order
class OnnxRuntimeSession:
    backend = "onnxruntime"

    def __init__(self, path: str, threads: int | None = None):
        import onnxruntime as ort

        opts = ort.SessionOptions()
        opts.log_severity_level = 3
        # onnxruntime's memory-reuse planner is quadratic in the number of values (minutes to open
        # an unrolled T = 270 model); without it the session opens in seconds
        opts.enable_mem_reuse = False
        if threads:
            opts.intra_op_num_threads = int(threads)
        try:
            self.session = ort.InferenceSession(path, opts, providers=["CPUExecutionProvider"])
        except Exception as ex:  # onnxruntime's InvalidProtobuf, InvalidGraph, Fail...: a damaged file
            raise RunnerError(f"ONNX Runtime cannot load it ({type(ex).__name__}); it is damaged or not "
                              "an ONNX model: compile the artefact again", field=os.path.basename(path)) from None
        self.output_names = [o.name for o in self.session.get_outputs()]

    def run(self, feeds: dict) -> list:
        return self.session.run(self.output_names, feeds)


class TensorRTSession:
    """A TensorRT engine (``*.plan`` from build_engine.sh) run through pycuda.

    TensorRT >= 8.5 uses named tensors (set_input_shape / set_tensor_address / execute_async_v3),
    TensorRT 8.2 (JetPack 4.6) bindings (set_binding_shape / execute_v2); both are handled.
    """

    backend = "tensorrt"

    def __init__(self, plan_path: str, output_names: list):
        import pycuda.autoinit  # noqa: F401  (creates the CUDA context)
        import pycuda.driver as cuda
        import tensorrt as trt

        self.cuda, self.trt = cuda, trt
        logger = trt.Logger(trt.Logger.WARNING)
        with open(plan_path, "rb") as f:
            self.engine = trt.Runtime(logger).deserialize_cuda_engine(f.read())
        if self.engine is None:
            raise RunnerError("TensorRT could not load the engine (built by another TensorRT version?)", field=plan_path)
        self.context = self.engine.create_execution_context()
        self.output_names = list(output_names)
        self.named = hasattr(self.engine, "num_io_tensors")

    def run(self, feeds: dict) -> list:
        cuda, trt, ctx, eng = self.cuda, self.trt, self.context, self.engine
        device = []
        if self.named:
            for name, arr in feeds.items():
                arr = np.ascontiguousarray(arr, dtype=np.float32)
                ctx.set_input_shape(name, arr.shape)
                buf = cuda.mem_alloc(max(arr.nbytes, 1))
                cuda.memcpy_htod(buf, arr)
                ctx.set_tensor_address(name, int(buf))
                device.append(buf)
            outs = []
            for name in self.output_names:
                shape = tuple(ctx.get_tensor_shape(name))
                host = np.empty(shape, dtype=trt.nptype(eng.get_tensor_dtype(name)))
                buf = cuda.mem_alloc(max(host.nbytes, 1))
                ctx.set_tensor_address(name, int(buf))
                device.append(buf)
                outs.append((host, buf))
            stream = cuda.Stream()
            ctx.execute_async_v3(stream.handle)
            stream.synchronize()
        else:
            bindings = [0] * eng.num_bindings
            for name, arr in feeds.items():
                arr = np.ascontiguousarray(arr, dtype=np.float32)
                idx = eng.get_binding_index(name)
                ctx.set_binding_shape(idx, arr.shape)
                buf = cuda.mem_alloc(max(arr.nbytes, 1))
                cuda.memcpy_htod(buf, arr)
                bindings[idx] = int(buf)
                device.append(buf)
            outs = []
            for name in self.output_names:
                idx = eng.get_binding_index(name)
                host = np.empty(tuple(ctx.get_binding_shape(idx)), dtype=trt.nptype(eng.get_binding_dtype(idx)))
                buf = cuda.mem_alloc(max(host.nbytes, 1))
                bindings[idx] = int(buf)
                device.append(buf)
                outs.append((host, buf))
            ctx.execute_v2(bindings)
        for host, buf in outs:
            cuda.memcpy_dtoh(host, buf)
        return [host.astype(np.float32) for host, _ in outs]


def tensorrt_available() -> bool:
    try:
        import pycuda.driver  # noqa: F401
        import tensorrt  # noqa: F401
    except Exception:
        return False
    return True


def open_session(directory: str, variant: dict, backend: str = "auto", threads: int | None = None):
    """A session for one variant: TensorRT if asked/auto and possible, else ONNX Runtime."""
    path = artefact_file(directory, variant.get("file"), f"manifest.json/variants/{variant.get('name')}/file")
    plan = artefact_file(directory, variant["file"].replace(".onnx", ".plan"), "engine")
    names = [o["name"] for o in variant["outputs"]]
    if backend not in ("auto", "tensorrt", "onnxruntime"):
        raise RunnerError("backend must be auto, tensorrt or onnxruntime", field="--backend")
    if backend == "tensorrt" or (backend == "auto" and os.path.isfile(plan) and tensorrt_available()):
        if not tensorrt_available():
            raise RunnerError("tensorrt (with pycuda) is not importable here", field="--backend")
        if not os.path.isfile(plan):
            raise RunnerError(f"no engine {os.path.basename(plan)}: run build_engine.sh on the board first", field="--backend")
        return TensorRTSession(plan, names)
    if not os.path.isfile(path):
        raise RunnerError(f"missing {variant['file']}", field=str(directory))
    return OnnxRuntimeSession(path, threads)


def prepare_input(manifest: dict, x) -> np.ndarray:
    """(T, C) or (B, T, C) -> float32 (B, T, C) checked against the manifest; frames (B, T, *frame_shape)
    of a convolutional model are flattened in C order first."""
    x = np.asarray(x)
    frame = tuple(manifest["input"].get("frame_shape") or ())
    if frame and x.ndim in (len(frame) + 1, len(frame) + 2) and tuple(x.shape[-len(frame):]) == frame:
        x = x.reshape(x.shape[:-len(frame)] + (int(np.prod(frame)),))
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3:
        raise RunnerError(f"input must have shape (T, C) or (B, T, C), got {x.shape}", field="input")
    spec = manifest["input"]
    c = spec["channels"]
    if x.shape[2] != c:
        hint = (f" (the model applies its {spec['input_copies']} input copies itself: pass the data's {c} channels)"
                if x.shape[2] == spec["graph_width"] and spec["input_copies"] > 1 else "")
        raise RunnerError(f"input has {x.shape[2]} channels, the model takes {c}{hint}", field="input")
    if x.dtype == np.bool_ or np.issubdtype(x.dtype, np.number):
        x = x.astype(np.float32)
    else:
        raise RunnerError(f"input dtype {x.dtype} is not numeric", field="input")
    if not np.all(np.isfinite(x)):
        raise RunnerError("input contains NaN or Inf", field="input")
    return np.ascontiguousarray(x)


def score_from_sequence(mode: str, seq: np.ndarray) -> np.ndarray:
    if mode == "membrane_max":
        return seq.max(axis=1)
    if mode == "last":
        return seq[:, -1]
    return seq.sum(axis=1)


def _result(manifest: dict, score: np.ndarray, seq: np.ndarray | None) -> dict:
    out_names = [o["name"] for o in _variant(manifest, "sequence")["outputs"]]
    res = {out_names[0]: score.astype(np.float32), "prediction": np.argmax(score, axis=1).astype(np.int64)}
    if seq is not None:
        name = out_names[1] if len(out_names) > 1 else "outputs"
        res[name] = seq.astype(np.uint8) if name == "output_spikes" else seq.astype(np.float32)
    return res


class ArtefactRunner:
    """Runs the artefact in ``directory``: ``run(x)`` (sequence model) or ``stream(x)`` (step model)."""

    def __init__(self, directory: str, backend: str = "auto", threads: int | None = None):
        self.directory = str(directory)
        self.manifest = load_manifest(self.directory)
        self.backend_choice, self.threads = backend, threads
        self._sessions: dict = {}

    def session(self, name: str):
        if name not in self._sessions:
            self._sessions[name] = open_session(self.directory, _variant(self.manifest, name),
                                                self.backend_choice, self.threads)
        return self._sessions[name]

    @property
    def backend(self) -> str:
        return self.session("sequence").backend

    def run(self, x) -> dict:
        """The whole sample through model.onnx (T must equal the manifest's for unrolled SNNs)."""
        x = prepare_input(self.manifest, x)
        m = self.manifest
        if m["time_axis"] != "dynamic" and x.shape[1] != m["time_steps"]:
            raise RunnerError(f"input has {x.shape[1]} time steps, model.onnx was exported for "
                              f"{m['time_steps']} (use streaming mode for any T)", field="input")
        outs = self.session("sequence").run({m["input"]["name"]: x})
        return _result(m, outs[0], outs[1] if len(outs) > 1 else None)

    def stream(self, x) -> dict:
        """Feed step.onnx one time step at a time from zero state (any T)."""
        x = prepare_input(self.manifest, x)
        stepper = self.stepper(x.shape[0])
        ys = [stepper.push(x[:, t]) for t in range(x.shape[1])]
        seq = np.stack(ys, axis=1) if ys else np.zeros((x.shape[0], 0, len(self.manifest["classes"])), np.float32)
        return _result(self.manifest, score_from_sequence(self.manifest["readout"]["mode"], seq), seq)

    def stepper(self, batch: int) -> "Stepper":
        return Stepper(self.session("step"), _variant(self.manifest, "step"), batch)


class Stepper:
    """Online use: ``push(x_t)`` -> y_t, the state (I, V, refractory, delay lines) kept here."""

    def __init__(self, session, variant: dict, batch: int):
        self.session, self.variant, self.batch = session, variant, batch
        self.x_name = variant["inputs"][0]["name"]
        self.reset()

    def reset(self) -> None:
        self.state = {s["input"]: np.zeros([self.batch] + [int(d) for d in s["shape"][1:]], np.float32)
                      for s in self.variant["state"]}

    def push(self, x_t) -> np.ndarray:
        x_t = np.ascontiguousarray(np.asarray(x_t, dtype=np.float32).reshape(self.batch, -1))
        outs = self.session.run({self.x_name: x_t, **self.state})
        self.state = {s["input"]: v for s, v in zip(self.variant["state"], outs[1:])}
        return outs[0]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Run an snncc Jetson artefact (TensorRT if importable, else ONNX Runtime).")
    ap.add_argument("--dir", default=os.path.dirname(os.path.abspath(__file__)), help="artefact directory")
    ap.add_argument("--input", required=True, help=".npy of shape (T, C) or (B, T, C)")
    ap.add_argument("--stream", action="store_true", help="feed step.onnx one time step at a time")
    ap.add_argument("-o", "--output", help="write the results to this .npz")
    ap.add_argument("--backend", default="auto", choices=["auto", "tensorrt", "onnxruntime"])
    args = ap.parse_args(argv)
    try:
        runner = ArtefactRunner(args.dir, args.backend)
        x = np.load(args.input, allow_pickle=False)
        res = runner.stream(x) if args.stream else runner.run(x)
    except (RunnerError, OSError, ValueError) as ex:
        print(f"run.py: error: {ex}", file=sys.stderr)
        return 2
    if args.output:
        np.savez(args.output, **res)
    classes = runner.manifest["classes"]
    print(json.dumps({"backend": runner.session("step" if args.stream else "sequence").backend,
                      "prediction": [classes[i] for i in res["prediction"].tolist()]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
