"""The encoded data-set file the models, ``snncc train`` and ``snncc check`` eat.

A ``.npz`` (``numpy.savez_compressed`` content, written atomically) with exactly three keys:

* ``inputs`` (N, T, C): ``kind == "events"`` -> uint8 0/1, C = 24, channel = 2*taxel + polarity
  (input copies NOT applied: use ``tile_copies``); ``kind == "frames"`` -> float32, C = 12;
* ``labels`` (N,) int64 in 0..26 (index in ``['Space', 'A', ..., 'Z']``);
* ``meta`` a JSON string: kind, threshold, time_bin_size_ms, dt_s, n_steps, classes, synthetic,
  source, seed (others may be added).

``load_dataset`` reads with ``allow_pickle=False`` and validates keys, shapes, dtypes and values.
"""

from __future__ import annotations

import json
import os
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from snncc.atomic import atomic_path
from snncc.data.letters import CLASSES, N_CLASSES, N_TAXELS
from snncc.errors import SnnccError

KEYS = ("inputs", "labels", "meta")
META_KEYS = ("kind", "threshold", "time_bin_size_ms", "dt_s", "n_steps", "classes", "synthetic",
             "source", "seed")


def _validate(inputs: np.ndarray, labels: np.ndarray, meta: dict, f: str | None) -> None:
    kind = meta.get("kind")
    if kind not in ("events", "frames"):
        raise SnnccError(f"kind must be 'events' or 'frames', got {kind!r}", file=f, field="meta.kind")
    for k in META_KEYS:
        if k not in meta:
            raise SnnccError("missing key", file=f, field=f"meta.{k}")
    if inputs.ndim != 3:
        raise SnnccError(f"expected (N, T, C), got shape {inputs.shape}", file=f, field="inputs")
    n, t, c = inputs.shape
    if kind == "events":
        if inputs.dtype != np.uint8:
            raise SnnccError(f"event inputs must be uint8, got {inputs.dtype}", file=f, field="inputs")
        if c != 2 * N_TAXELS:
            raise SnnccError(f"event inputs need {2 * N_TAXELS} channels (no input copies), got {c}",
                             file=f, field="inputs")
        if inputs.size and inputs.max() > 1:
            raise SnnccError("event inputs must be binary (0/1)", file=f, field="inputs")
    else:
        if inputs.dtype != np.float32:
            raise SnnccError(f"frame inputs must be float32, got {inputs.dtype}", file=f, field="inputs")
        if c != N_TAXELS:
            raise SnnccError(f"frame inputs need {N_TAXELS} channels, got {c}", file=f, field="inputs")
        if not np.all(np.isfinite(inputs)):
            raise SnnccError("NaN or Inf in frame inputs", file=f, field="inputs")
    if labels.dtype != np.int64 or labels.shape != (n,):
        raise SnnccError(f"labels must be int64 of shape ({n},), got {labels.dtype} {labels.shape}",
                         file=f, field="labels")
    if labels.size and (labels.min() < 0 or labels.max() >= N_CLASSES):
        raise SnnccError(f"labels must be in 0..{N_CLASSES - 1}", file=f, field="labels")
    classes = meta.get("classes")
    if not isinstance(classes, list) or not classes or not all(isinstance(c, str) for c in classes):
        raise SnnccError("must be a non-empty list of class names (label i names classes[i])", file=f,
                         field="meta.classes")
    if labels.size and labels.max() >= len(classes):
        raise SnnccError(f"names {len(classes)} classes but the labels reach {int(labels.max())}; every label "
                         "must name one of the classes", file=f, field="meta.classes")
    if meta.get("n_steps") != t:
        raise SnnccError(f"n_steps {meta.get('n_steps')} does not match inputs' T = {t}", file=f,
                         field="meta.n_steps")


def save_dataset(path: str | os.PathLike, inputs: np.ndarray, labels: np.ndarray, meta: dict[str, Any]) -> None:
    """Validate and write the data-set file atomically (no partial file on failure)."""
    meta = dict(meta)
    meta.setdefault("classes", list(CLASSES))
    inputs = np.asarray(inputs)
    if meta.get("kind") == "events" and inputs.dtype == np.bool_:
        inputs = inputs.astype(np.uint8)
    if meta.get("kind") == "frames" and inputs.dtype != np.float32:
        inputs = inputs.astype(np.float32)
    labels = np.asarray(labels)
    if labels.dtype != np.int64 and np.issubdtype(labels.dtype, np.integer):
        labels = labels.astype(np.int64)
    meta.setdefault("n_steps", int(inputs.shape[1]) if inputs.ndim == 3 else None)
    _validate(inputs, labels, meta, str(path))
    text = json.dumps(meta, sort_keys=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:  # a file object: savez must not append '.npz' to the temp name
            np.savez_compressed(fh, inputs=inputs, labels=labels, meta=np.array(text))


def load_dataset(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Read and validate a data-set file: ``(inputs, labels, meta)``."""
    f = str(path)
    p = Path(path)
    if not p.is_file():
        raise SnnccError("file not found", file=f, field="path")
    try:
        with np.load(p, allow_pickle=False) as z:
            keys = set(z.files)
            missing = [k for k in KEYS if k not in keys]
            if missing:
                raise SnnccError(f"missing key (have {sorted(keys)})", file=f, field=missing[0])
            extra = sorted(keys - set(KEYS))
            if extra:
                raise SnnccError(f"unexpected key (allowed: {', '.join(KEYS)})", file=f, field=extra[0])
            inputs, labels, meta_arr = z["inputs"], z["labels"], z["meta"]
    except SnnccError:
        raise
    except (zipfile.BadZipFile, zlib.error, ValueError, OSError, EOFError, KeyError) as ex:
        raise SnnccError(f"not a readable .npz data set ({type(ex).__name__})", file=f, field="format") from None
    if meta_arr.ndim != 0 or meta_arr.dtype.kind != "U":
        raise SnnccError("meta must be a JSON string", file=f, field="meta")
    try:
        meta = json.loads(str(meta_arr))
    except json.JSONDecodeError:
        raise SnnccError("meta is not valid JSON", file=f, field="meta") from None
    if not isinstance(meta, dict):
        raise SnnccError("meta must be a JSON object", file=f, field="meta")
    _validate(inputs, labels, meta, f)
    return inputs, labels, meta

