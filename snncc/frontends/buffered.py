"""Checkpoints of the buffered classifiers (FCN, ResNet, Encoder, TCNN, Inception) at compile time.

They have no IR graph (the IR has no convolutions): ``--target jetson`` exports the PyTorch module
directly (``snncc.targets.jetson.buffered``), checked in ONNX Runtime against PyTorch; any other
target is refused in one line.
"""

from __future__ import annotations

from pathlib import Path

from snncc.errors import SnnccError


def compile_buffered(path: str | Path, target: str, options: dict):
    """The Jetson artefact of a buffered-classifier checkpoint, or None when ``path`` holds another model."""
    from snncc.targets.jetson.buffered import buffered_checkpoint, lower_checkpoint

    if Path(path).suffix.lower() not in (".pt", ".pth", ".ckpt"):
        return None
    try:
        obj = buffered_checkpoint(path)
    except SnnccError:
        return None          # not a readable torch file: the regular loader says why
    if obj is None:
        return None
    kind = obj["architecture"]["kind"]
    if target != "jetson":
        raise SnnccError(f"a {kind} (convolutional, buffered) has no IR graph and compiles only with --target jetson",
                         file=str(path), field="--target")
    from snncc.targets import get_target, target_options

    typed = target_options(get_target("jetson"), options)   # refuses an option Jetson does not take
    return lower_checkpoint(path, obj, typed.as_dict())
