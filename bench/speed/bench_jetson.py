#!/usr/bin/env python3
"""Jetson artefact latency on this machine (ONNX Runtime, CPU) against naive PyTorch eager loops.

The paper-sized RSNN (48 -> 450 recurrent -> 28, 270 steps, SpyTorch update order) is compiled
with the Jetson target; its model.onnx is timed at batch 1 in ONNX Runtime side by side, in the
same run and on the same inputs, with the per-step PyTorch eager loop of the same network
(``SpikingClassifier.forward``, the authors' style of loop). Goal: >= 5x faster. The paper's LSTM
(12 -> 228 -> 27, 54 frames) is timed the same way against ``nn.LSTM`` in eager PyTorch.
Both sides use the same number of threads (default 1: a shared machine times more stably).
The networks have random (untrained) weights: latency does not depend on them.

    python bench/speed/bench_jetson.py [--samples 20] [--repeats 3] [--threads 1] [--json-out FILE]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from snncc.frontends import graph_from_object
from snncc.models.lstm import LSTMClassifier, LSTMConfig
from snncc.models.snn import SNNConfig, SpikingClassifier
from snncc.targets.jetson import target
from snncc.targets.jetson.standalone_runner import ArtefactRunner


def per_sample_ms(fn, inputs: np.ndarray, repeats: int) -> list[float]:
    """Median-friendly: per repeat, predict every sample at batch 1; ms per sample."""
    fn(inputs[:1])  # warm-up
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for i in range(len(inputs)):
            fn(inputs[i:i + 1])
        out.append((time.perf_counter() - t0) / len(inputs) * 1e3)
    return out


def summary(ms: list[float]) -> dict:
    return {"median_ms": statistics.median(ms), "spread_ms": max(ms) - min(ms), "per_repeat_ms": ms}


def bench_rsnn(workdir: Path, samples: int, repeats: int) -> dict:
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig()).eval()   # 24 x 2 copies -> 450 rec -> 28, spytorch order
    graph = graph_from_object(model)
    t0 = time.perf_counter()
    artefact = target.lower(graph, {})              # T = 1.35 s / 5 ms = 270, validated on the way
    lower_s = time.perf_counter() - t0
    artefact.write(workdir / "rsnn")
    runner = ArtefactRunner(str(workdir / "rsnn"), backend="onnxruntime", threads=torch.get_num_threads())
    steps = artefact.manifest["time_steps"]
    x = (np.random.default_rng(0).random((samples, steps, 24)) < 0.1).astype(np.float32)

    def eager(xb):
        with torch.no_grad():
            return model(torch.as_tensor(xb))[0].sum(dim=1).argmax(dim=1)

    onnx_pred = runner.run(x)["prediction"]
    eager_pred = np.concatenate([eager(x[i:i + 1]).numpy() for i in range(samples)])
    ort_ms = per_sample_ms(runner.run, x, repeats)
    eager_ms = per_sample_ms(eager, x, repeats)
    stream_ms = per_sample_ms(runner.stream, x[: max(2, samples // 4)], repeats)
    return {
        "network": "RSNN 48 (24 x 2 copies) -> 450 recurrent -> 28, 270 steps, spytorch order",
        "lower_seconds": lower_s,
        "onnxruntime_sequence": summary(ort_ms),
        "onnxruntime_step_streaming": summary(stream_ms),
        "pytorch_eager_loop": summary(eager_ms),
        "speedup_vs_eager": statistics.median(eager_ms) / statistics.median(ort_ms),
        "predictions_equal_eager_vs_onnx": bool(np.array_equal(onnx_pred, eager_pred)),
        "validation": {k: v for k, v in artefact.manifest["validation"]["sequence"].items() if k != "operators"},
        "fp16": artefact.manifest["validation"]["fp16"],
        "onnx_nodes": sum(artefact.manifest["validation"]["sequence"]["operators"].values()),
    }


def bench_lstm(workdir: Path, samples: int, repeats: int) -> dict:
    torch.manual_seed(0)
    model = LSTMClassifier(LSTMConfig()).eval()     # 12 -> 228 -> 27, frames at 40 Hz
    artefact = target.lower(graph_from_object(model), {})
    artefact.write(workdir / "lstm")
    runner = ArtefactRunner(str(workdir / "lstm"), backend="onnxruntime", threads=torch.get_num_threads())
    steps = artefact.manifest["time_steps"]
    x = np.random.default_rng(1).standard_normal((samples, steps, 12)).astype(np.float32)

    def eager(xb):
        with torch.no_grad():
            return model(torch.as_tensor(xb)).argmax(dim=1)

    ort_ms = per_sample_ms(runner.run, x, repeats)
    eager_ms = per_sample_ms(eager, x, repeats)
    return {
        "network": f"LSTM 12 -> 228 -> 27, {steps} steps (native ONNX LSTM op)",
        "onnxruntime_sequence": summary(ort_ms),
        "pytorch_eager_nn_lstm": summary(eager_ms),
        "speedup_vs_eager": statistics.median(eager_ms) / statistics.median(ort_ms),
        "predictions_equal_eager_vs_onnx": bool(np.array_equal(
            runner.run(x)["prediction"], np.concatenate([eager(x[i:i + 1]).numpy() for i in range(samples)]))),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--samples", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--json-out", type=Path)
    args = ap.parse_args(argv)
    torch.set_num_threads(args.threads)
    with tempfile.TemporaryDirectory() as tmp:
        record = {
            "machine": "this machine's CPU via ONNX Runtime (not a Jetson; no TensorRT here)",
            "threads": args.threads, "samples": args.samples, "repeats": args.repeats,
            "rsnn": bench_rsnn(Path(tmp), args.samples, args.repeats),
            "lstm": bench_lstm(Path(tmp), args.samples, args.repeats),
        }
    text = json.dumps(record, indent=2)
    print(text)
    if args.json_out:
        args.json_out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
