"""Data for training: an encoded ``.npz`` (``snncc data encode``) or a directory of published pickles.

Spiking models and the eLSTM take binary events (N, T, 24) binned at the preset's time_bin_size;
the LSTM takes inverted frames (N, T, 12) at 40 Hz. A directory of pickles is encoded on the fly
in memory, exactly as ``snncc data encode`` / ``snncc data frames`` would (nothing is written).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from snncc.errors import SnnccError

EVENT_KINDS = ("rsnn", "ffsnn", "elstm")
FRAME_DT_S = 0.025


@dataclass
class TrainingData:
    inputs: torch.Tensor          # (N, T, C) uint8 events or float32 frames
    labels: torch.Tensor          # (N,) int64
    meta: dict = field(default_factory=dict)
    source: str = ""

    @property
    def encoding(self) -> str:
        return self.meta.get("kind") or ("events" if self.inputs.shape[-1] == 24 else "frames")

    def facts(self) -> dict:
        """Data facts recorded in checkpoints."""
        m = self.meta
        return {
            "source": self.source,
            "encoding": self.encoding,
            "samples": int(self.inputs.shape[0]),
            "steps": int(self.inputs.shape[1]),
            "channels": int(self.inputs.shape[2]),
            "threshold": m.get("threshold"),
            "time_bin_size_ms": m.get("time_bin_size_ms"),
            "dt_s": m.get("dt_s"),
            "synthetic": bool(m.get("synthetic", False)),
            "classes": m.get("classes"),
        }


def _load_npz(path: Path) -> tuple[np.ndarray, np.ndarray, dict]:
    from snncc.data.dataset_file import load_dataset

    return load_dataset(path)


def _encode_directory(path: Path, kind: str, threshold: int, time_bin_size: float) -> tuple[np.ndarray, np.ndarray, dict]:
    """Events (``snncc data encode``) or frames (``snncc data frames``) of a directory of pickles."""
    from snncc.data.encoding import encode_events, frame_set

    if kind in EVENT_KINDS:
        encoded = encode_events(path, threshold, time_bin_size)
    else:
        encoded = frame_set(path)
    return encoded.inputs, encoded.labels, encoded.meta


def load_training_data(path: str | Path, kind: str, threshold: int, time_bin_size: float) -> TrainingData:
    """Inputs and labels for model ``kind``, checked against the encoding it needs."""
    path = Path(path)
    if path.is_dir():
        inputs, labels, meta = _encode_directory(path, kind, threshold, time_bin_size)
    elif path.is_file():
        inputs, labels, meta = _load_npz(path)
    else:
        raise SnnccError("no such file or directory", file=str(path), field="--data")
    meta = dict(meta or {})
    channels = inputs.shape[-1]
    if kind in EVENT_KINDS:
        if channels != 24:
            raise SnnccError(f"{kind} needs events (24 channels); this set has {channels} channels "
                             "(frames?) -- encode it with snncc data encode", file=str(path), field="inputs")
        data_th = meta.get("threshold")
        if data_th is not None and float(data_th) != float(threshold):
            raise SnnccError(f"events encoded at threshold {data_th} but --threshold is {threshold}",
                             file=str(path), field="meta.threshold")
        data_bin = meta.get("time_bin_size_ms")
        if data_bin is not None and not math.isclose(float(data_bin), float(time_bin_size)):
            raise SnnccError(f"events binned at {data_bin} ms but the preset uses time_bin_size {time_bin_size:g} ms; "
                             f"re-encode or pass --set time_bin_size={data_bin}", file=str(path), field="meta.time_bin_size_ms")
    elif channels != 12:
        raise SnnccError(f"{kind} needs frames (12 taxels); this set has {channels} channels "
                         "(use elstm, rsnn or ffsnn for events)", file=str(path), field="inputs")
    x = torch.from_numpy(np.ascontiguousarray(inputs))
    if kind not in EVENT_KINDS:
        x = x.to(torch.float32)
    y = torch.from_numpy(np.asarray(labels, dtype=np.int64))
    if x.shape[0] != y.shape[0] or x.shape[0] == 0:
        raise SnnccError(f"{x.shape[0]} inputs but {y.shape[0]} labels", file=str(path), field="labels")
    return TrainingData(x, y, meta, str(path))


def subset_indices(labels: np.ndarray, n: int | None, seed: int) -> np.ndarray:
    """A seeded subset of ``n`` samples with the classes in proportion (largest remainders), sorted.

    All samples when ``n`` is None or not smaller than the set.
    """
    labels = np.asarray(labels)
    if n is None or n >= labels.size:
        return np.arange(labels.size)
    classes, counts = np.unique(labels, return_counts=True)
    if n < 2 * classes.size:
        raise SnnccError(f"a subset needs at least 2 samples per class ({2 * classes.size}), got {n}", field="--subset")
    quota = counts * (n / labels.size)
    take = np.floor(quota).astype(np.int64)
    extra = np.argsort(-(quota - take), kind="stable")[: n - int(take.sum())]
    take[extra] += 1
    rng = np.random.default_rng(seed)
    chosen = [rng.permutation(np.flatnonzero(labels == c))[:k] for c, k in zip(classes, take)]
    return np.sort(np.concatenate(chosen))
