"""Loaders and writers of the published Braille files (Zenodo 6556273 = release 1, 7050094 = 2).

Layouts (docs/braille.md, "The published files"):

* raw frames ``data_braille_letters_raw.pkl``: release 1 a pickled ``list`` of ``dict``, release 2
  a pickled ``pandas.DataFrame``; each record has ``letter`` (``'Space'``, ``'A'``..``'Z'``) and
  ``taxel_data`` (T x 12 raw 8-bit counts, 255 at rest, *not* inverted);
* events ``data_braille_letters_th_{th}.pkl``: the same containers with ``letter`` and ``events``,
  a list of 12 taxels, each ``[ON_times, OFF_times]`` (float seconds from the first frame,
  chronological).

Label = index in ``['Space', 'A', ..., 'Z']``. Extra columns (e.g. ``timestamp``) are ignored.

Security: the published files are pickles. They are read with a restricted unpickler
(:mod:`snncc.data.safe_pickle`) that rebuilds only lists, dicts, numpy arrays and pandas DataFrames
and refuses any other name a pickle asks for, before calling it: a file from the internet cannot
run code through snncc.
"""

from __future__ import annotations

import os
import pickle
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from snncc.atomic import atomic_path
from snncc.data.safe_pickle import load_published_pickle
from snncc.data.letters import CLASSES, N_TAXELS, label_of
from snncc.data.sigma_delta import Events
from snncc.errors import SnnccError

RAW_NAME = "data_braille_letters_raw.pkl"
THRESHOLDS = (1, 2, 5, 10)


def events_name(threshold: float) -> str:
    th = int(threshold) if float(threshold).is_integer() else threshold
    return f"data_braille_letters_th_{th}.pkl"


@dataclass
class RawSet:
    """Raw frames as published: ``raw`` (N, T, 12) int64 counts (255 at rest), labels (N,)."""

    raw: np.ndarray
    labels: np.ndarray
    source: str = ""
    release: int = 1

    def inverted(self) -> np.ndarray:
        """The frames the encoder eats: ``255 - raw`` (0 at rest, 255 at full load), int64."""
        return 255 - self.raw


@dataclass
class EventSet:
    events: Events
    labels: np.ndarray
    source: str = ""
    release: int = 1


# --------------------------------------------------------------------------- reading


def _records(obj: Any, path: Path, needed: str) -> tuple[list, list, int]:
    """Letters, payloads (column ``needed``) and release (1 list of dicts, 2 DataFrame)."""
    import pandas as pd

    f = str(path)
    if isinstance(obj, pd.DataFrame):
        for col in ("letter", needed):
            if col not in obj.columns:
                raise SnnccError(f"missing column (have {sorted(map(str, obj.columns))})", file=f, field=col)
        return list(obj["letter"]), list(obj[needed]), 2
    if isinstance(obj, dict):  # a dict of columns, as some scripts save it
        for col in ("letter", needed):
            if col not in obj:
                raise SnnccError(f"missing column (have {sorted(map(str, obj))})", file=f, field=col)
        cols = []
        for col in ("letter", needed):
            v = obj[col]
            if isinstance(v, (str, bytes, dict)) or not hasattr(v, "__len__") or not hasattr(v, "__iter__"):
                raise SnnccError(f"a column must be a list, got {type(v).__name__}", file=f, field=col)
            cols.append(list(v))
        letters, payload = cols
        if len(letters) != len(payload):
            raise SnnccError("columns 'letter' and '%s' differ in length" % needed, file=f, field=needed)
        return letters, payload, 2
    if isinstance(obj, (list, tuple)):
        letters, payload = [], []
        for i, rec in enumerate(obj):
            if not isinstance(rec, dict):
                raise SnnccError(f"expected a dict per sample, got {type(rec).__name__}", file=f,
                                 field=f"sample {i}")
            for col in ("letter", needed):
                if col not in rec:
                    raise SnnccError("missing key", file=f, field=f"sample {i}.{col}")
            letters.append(rec["letter"])
            payload.append(rec[needed])
        return letters, payload, 1
    raise SnnccError(
        f"expected a list of dicts or a pandas DataFrame, got {type(obj).__name__}", file=f, field="format"
    )


def _labels(letters: Sequence, f: str) -> np.ndarray:
    return np.array([label_of(l, file=f, field=f"sample {i}.letter") for i, l in enumerate(letters)],
                    dtype=np.int64)


def _samples(path: str | os.PathLike, key: str) -> tuple[np.ndarray, Sequence, str]:
    """(labels, per-sample ``key`` payloads, release) of a published pickle; no samples is an error."""
    path = Path(path)
    letters, payload, release = _records(load_published_pickle(path), path, key)
    if not letters:
        raise SnnccError("no samples", file=str(path), field=key)
    return _labels(letters, str(path)), payload, release


def load_raw(path: str | os.PathLike) -> RawSet:
    """Read a published raw-frame file (either release); validated, labels 0..26."""
    f = str(Path(path))
    labels, payload, release = _samples(path, "taxel_data")
    frames = []
    n_frames = None
    for i, td in enumerate(payload):
        fld = f"sample {i}.taxel_data"
        try:
            a = np.asarray(td, dtype=np.float64)
        except (TypeError, ValueError):
            raise SnnccError("not a numeric T x 12 array", file=f, field=fld) from None
        if a.ndim != 2:
            raise SnnccError(f"expected T x {N_TAXELS} frames, got shape {a.shape}", file=f, field=fld)
        if a.shape[1] != N_TAXELS:
            raise SnnccError(f"expected {N_TAXELS} taxels, got {a.shape[1]}", file=f, field=fld)
        if a.shape[0] < 2:
            raise SnnccError(f"need at least 2 frames, got {a.shape[0]}", file=f, field=fld)
        if n_frames is None:
            n_frames = a.shape[0]
        elif a.shape[0] != n_frames:
            raise SnnccError(f"{a.shape[0]} frames, but sample 0 has {n_frames} (all must match)",
                             file=f, field=fld)
        if not np.all(np.isfinite(a)):
            raise SnnccError("NaN or Inf in raw counts", file=f, field=fld)
        if np.any(a < 0) or np.any(a > 255) or np.any(a != np.round(a)):
            raise SnnccError("raw counts must be integers in 0..255 (8-bit)", file=f, field=fld)
        frames.append(a)
    raw = np.stack(frames).astype(np.int64)
    return RawSet(raw=raw, labels=labels, source=f, release=release)


def _times(seq: Any, f: str, fld: str) -> np.ndarray:
    try:
        t = np.asarray(seq if seq is not None else [], dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise SnnccError("event times must be a list of numbers (seconds)", file=f, field=fld) from None
    if t.size:
        if not np.all(np.isfinite(t)):
            raise SnnccError("NaN or Inf event time", file=f, field=fld)
        if np.any(t < 0):
            raise SnnccError("negative event time", file=f, field=fld)
        if np.any(np.diff(t) < 0):
            raise SnnccError("event times are not chronological", file=f, field=fld)
    return t


def load_events(path: str | os.PathLike) -> EventSet:
    """Read a published event file (either release): 12 taxels x [ON_times, OFF_times] per sample."""
    f = str(Path(path))
    labels, payload, release = _samples(path, "events")
    s_l, tx_l, p_l, t_l = [], [], [], []
    for i, ev in enumerate(payload):
        fld = f"sample {i}.events"
        if not isinstance(ev, (list, tuple, np.ndarray)) or len(ev) != N_TAXELS:
            n = len(ev) if hasattr(ev, "__len__") else type(ev).__name__
            raise SnnccError(f"expected {N_TAXELS} taxels, got {n}", file=f, field=fld)
        for k, pair in enumerate(ev):
            if not isinstance(pair, (list, tuple, np.ndarray)) or len(pair) != 2:
                raise SnnccError("expected [ON_times, OFF_times]", file=f, field=f"{fld}[{k}]")
            on = _times(pair[0], f, f"{fld}[{k}][0] (ON)")
            off = _times(pair[1], f, f"{fld}[{k}][1] (OFF)")
            t = np.concatenate([on, off])
            pol = np.concatenate([np.zeros(on.size, np.int8), np.ones(off.size, np.int8)])
            order = np.argsort(t, kind="stable")
            t_l.append(t[order])
            p_l.append(pol[order])
            s_l.append(np.full(t.size, i, np.int64))
            tx_l.append(np.full(t.size, k, np.int64))
    cat = lambda xs, dt: np.concatenate(xs).astype(dt) if xs else np.zeros(0, dt)  # noqa: E731
    events = Events(cat(s_l, np.int64), cat(tx_l, np.int64), cat(p_l, np.int8), cat(t_l, np.float64),
                    n_samples=len(labels), n_taxels=N_TAXELS)
    return EventSet(events=events, labels=labels, source=f, release=release)


def sniff(path: str | os.PathLike) -> str:
    """``'raw'`` or ``'events'``: which published file this is (by its columns)."""
    import pandas as pd

    path = Path(path)
    obj = load_published_pickle(path)
    if isinstance(obj, pd.DataFrame):
        cols = set(map(str, obj.columns))
    elif isinstance(obj, dict):
        cols = set(map(str, obj))
    elif isinstance(obj, (list, tuple)) and obj and isinstance(obj[0], dict):
        cols = set(map(str, obj[0]))
    else:
        raise SnnccError("expected a list of dicts or a pandas DataFrame", file=str(path), field="format")
    if "taxel_data" in cols:
        return "raw"
    if "events" in cols:
        return "events"
    # neither column: let the loader the name suggests report exactly what is missing
    return "events" if "_th" in path.name else "raw"


# --------------------------------------------------------------------------- writing


def _dump(path: Path, letters: list[str], column: str, payload: list, release: int) -> None:
    if release not in (1, 2):
        raise SnnccError(f"release must be 1 or 2, got {release}", field="release")
    with atomic_path(path) as tmp:
        if release == 1:
            records = [{"letter": l, column: p} for l, p in zip(letters, payload)]
            with open(tmp, "wb") as fh:
                pickle.dump(records, fh, protocol=4)
        else:
            import pandas as pd

            df = pd.DataFrame({"letter": letters, column: pd.Series(payload, dtype=object)})
            df.to_pickle(tmp, compression=None, protocol=4)


def write_raw(path: str | os.PathLike, raw: np.ndarray, labels: np.ndarray, release: int = 1) -> None:
    """Write raw frames (N, T, 12) counts in the published layout of ``release`` (1 or 2)."""
    raw = np.asarray(raw)
    if raw.ndim != 3 or raw.shape[2] != N_TAXELS:
        raise SnnccError(f"expected raw frames (N, T, {N_TAXELS}), got {raw.shape}", field="taxel_data")
    letters = [CLASSES[int(l)] for l in labels]
    payload = [np.asarray(raw[i], dtype=np.int64) for i in range(raw.shape[0])]
    _dump(Path(path), letters, "taxel_data", payload, release)


def events_to_lists(events: Events) -> list[list[list[list[float]]]]:
    """Per sample: 12 taxels x [ON_times, OFF_times] as Python float lists (the published layout)."""
    n, c = events.n_samples, events.n_taxels
    key = (events.sample * c + events.taxel) * 2 + events.polarity
    order = np.lexsort((events.times, key))
    key_s, t_s = key[order], events.times[order]
    bounds = np.searchsorted(key_s, np.arange(n * c * 2 + 1))
    t_list = t_s.tolist()
    out = []
    for i in range(n):
        sample = []
        for k in range(c):
            base = (i * c + k) * 2
            sample.append([t_list[bounds[base]:bounds[base + 1]], t_list[bounds[base + 1]:bounds[base + 2]]])
        out.append(sample)
    return out


def write_events(path: str | os.PathLike, events: Events, labels: np.ndarray, release: int = 1) -> None:
    """Write events in the published layout of ``release`` (1 list of dicts, 2 DataFrame)."""
    letters = [CLASSES[int(l)] for l in labels]
    if len(letters) != events.n_samples:
        raise SnnccError(f"{len(letters)} labels for {events.n_samples} samples", field="labels")
    _dump(Path(path), letters, "events", events_to_lists(events), release)
