"""The files ``main.c`` reads and writes (``artefact/support.py`` states the layout), from and to numpy."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from snncc.targets.kit import SnnccError


def input_bytes(x: np.ndarray) -> bytes:
    """``x`` (B, T, C) 0/1 as an input.bin."""
    x = np.ascontiguousarray(np.asarray(x) != 0, dtype=np.uint8)
    b, t, c = x.shape
    return b"SNNI" + struct.pack("<III", b, t, c) + x.tobytes()


def read_outputs(path: Path, samples: int, steps: int, outputs: int) -> np.ndarray:
    """(B, T, N) uint8 output spikes from an output.bin, its header checked against what was run."""
    data = Path(path).read_bytes()
    if len(data) < 16 or data[:4] != b"SNNO":
        raise SnnccError("the program wrote no output header", file=str(path), field="output.bin")
    head = struct.unpack("<III", data[4:16])
    body = data[16:]
    if head != (samples, steps, outputs) or len(body) != samples * steps * outputs:
        raise SnnccError(f"the program wrote {len(body)} output bytes for header {head}; expected {samples} x {steps} "
                         f"x {outputs}", file=str(path), field="output.bin")
    return np.frombuffer(body, np.uint8).reshape(samples, steps, outputs).copy()


def read_trace(path: Path, samples: int, steps: int, sizes: list[int]) -> list[dict[str, np.ndarray]]:
    """Per population (in order), {"spikes", "current", "voltage"} (B, T, n) int64 from a trace.bin."""
    per_step = 3 * sum(sizes)
    raw = np.frombuffer(Path(path).read_bytes(), "<i4")
    if raw.size != samples * steps * per_step:
        raise SnnccError(f"the program traced {raw.size} values, expected {samples * steps * per_step}",
                         file=str(path), field="trace.bin")
    raw = raw.reshape(samples, steps, per_step).astype(np.int64)
    out, at = [], 0
    for n in sizes:
        out.append({"spikes": raw[:, :, at:at + n], "current": raw[:, :, at + n:at + 2 * n],
                    "voltage": raw[:, :, at + 2 * n:at + 3 * n]})
        at += 3 * n
    return out


__all__ = ["input_bytes", "read_outputs", "read_trace"]
