"""Jetson target: ONNX artefacts (whole-sequence and streaming step), a TensorRT recipe and a runner.

The package's face. ``target`` (the registered target), ``JetsonTarget`` and ``JetsonOptions`` live in
``capabilities.py`` (light: each capability imports its work on use). The parts:

    lower.py               graph -> validated JetsonArtefact (export.py, validate.py, manifest.py, recipe.py)
    buffered.py            a buffered classifier's artefact (its PyTorch module: no IR graph)
    check.py               the IR reference vs the artefact on a data set
    standalone_runner.py   run.py of every artefact (numpy + onnxruntime / tensorrt, never snncc)
    run_artefact.py        ``snncc run``'s work     bench_artefacts.py, bench_protocol.py, power.py  ``snncc bench``'s

Names below are resolved on first use, so choosing the target imports neither torch nor ONNX.
"""

from __future__ import annotations

import importlib

_HOMES = {
    "target": "capabilities", "JetsonTarget": "capabilities", "JetsonOptions": "capabilities",
    "JetsonArtefact": "lower", "runner_source": "lower", "resolve_steps": "lower", "JetsonCheckRecord": "check",
}

__all__ = ["target", "JetsonTarget", "JetsonOptions", "JetsonArtefact", "JetsonCheckRecord"]


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'snncc.targets.jetson' has no attribute {name!r}")
    return getattr(importlib.import_module(f"snncc.targets.jetson.{home}"), name)
