"""Model input sets from Braille data: sigma-delta events binned per time step, or inverted frames.

The library behind ``snncc data encode`` / ``snncc data frames`` (and training on a directory of
published pickles): events follow the authors' rule exactly (reference starts at x[0], one event
per threshold step, linearly interpolated times), bins are ``numpy.round(1000 t / bin)``, binary,
channel = 2 x taxel + polarity, 24 channels, input copies NOT applied (training tiles them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from snncc.errors import SnnccError

FRAME_MS = 25.0
PAPER_RECORD_MS = 1350.0


@dataclass
class EncodedSet:
    """Inputs (N, T, C), labels (N,), and the facts recorded with them."""

    inputs: np.ndarray
    labels: np.ndarray
    meta: dict = field(default_factory=dict)

    def summary(self, written: list[str]) -> dict:
        m = self.meta
        record = {"out": written, "samples": int(self.inputs.shape[0]), "n_steps": int(self.inputs.shape[1]),
                  "channels": int(self.inputs.shape[2]), "synthetic": m["synthetic"], "source": m["source"]}
        if m["kind"] == "events":
            record.update(threshold=m["threshold"], time_bin_size_ms=m["time_bin_size_ms"],
                          events=m["events_before_binning"], events_after_binning=m["events_after_binning"])
        return record


def _events_source(src: Path, threshold: float | None, prefer: str):
    """(event file or None, raw file or None, threshold) for ``src`` and the user's choices."""
    from snncc.data import braille_files, formats

    if src.is_dir():
        if threshold is None:
            raise SnnccError("give --threshold to pick the events of a directory", field="--threshold")
        ev_path = braille_files.events_file(src, threshold) if prefer in ("auto", "events") else None
        if ev_path is not None:
            return ev_path, None, threshold
        if prefer == "events":
            raise SnnccError(f"no {formats.events_name(threshold)} here", file=str(src), field="path")
        raw_path = braille_files.raw_file(src)
        if raw_path is None:
            raise SnnccError(f"neither {formats.events_name(threshold)} nor {formats.RAW_NAME} here", file=str(src), field="path")
        return None, raw_path, threshold
    if formats.sniff(src) == "events":
        if prefer == "raw":
            raise SnnccError("needs a raw-frame file", file=str(src), field="--from")
        from_name = braille_files.threshold_from_name(src)
        if threshold is None:
            threshold = from_name
        elif from_name is not None and float(threshold) != from_name:
            raise SnnccError(f"the file name says threshold {from_name:g}, --threshold says {threshold:g}",
                             file=str(src), field="--threshold")
        if threshold is None:
            raise SnnccError("cannot tell the threshold of this event file; give --threshold", file=str(src),
                             field="--threshold")
        return src, None, threshold
    if threshold is None:
        raise SnnccError("give --threshold to encode raw frames", field="--threshold")
    return None, src, threshold


def load_events(src: str | Path, threshold: float | None = None, prefer: str = "auto",
                record_ms: float | None = None):
    """(events, labels, threshold, recording length in ms, source file) from published files.

    ``prefer``: ``auto`` (a directory's event file for the threshold if present, else encode its
    raw frames), ``events`` or ``raw``. The recording length defaults to frames x 25 ms of the raw
    frames (also for an event file beside a raw file), else the paper's 1350 ms.
    """
    from snncc.data import braille_files, formats
    from snncc.data.binning import record_ms as frames_ms
    from snncc.data.sigma_delta import encode

    src = Path(src)
    if prefer not in ("auto", "events", "raw"):
        raise SnnccError(f"expected auto, events or raw, got {prefer!r}", field="--from")
    braille_files.require_exists(src)
    ev_path, raw_path, threshold = _events_source(src, threshold, prefer)
    if ev_path is not None:
        es = formats.load_events(ev_path)
        rec = record_ms
        if rec is None:
            beside = ev_path.parent / formats.RAW_NAME
            rec = float(frames_ms(formats.load_raw(beside).raw.shape[1])) if beside.is_file() else PAPER_RECORD_MS
        return es.events, es.labels, float(threshold), rec, str(ev_path)
    rs = formats.load_raw(raw_path)
    rec = record_ms if record_ms is not None else float(frames_ms(rs.raw.shape[1]))
    return encode(rs.inverted(), threshold), rs.labels, float(threshold), rec, str(raw_path)


def _meta(kind: str, source: str, threshold, bin_ms, dt_s: float, n_steps: int, extra: dict) -> dict:
    from snncc.data.letters import CLASSES
    from snncc.data.braille_files import synthetic_info

    syn = synthetic_info(Path(source))
    meta = {"kind": kind, "threshold": threshold, "time_bin_size_ms": bin_ms, "dt_s": dt_s,
            "n_steps": int(n_steps), "classes": list(CLASSES), "synthetic": syn is not None,
            "source": source, "seed": syn.get("seed") if syn else None,
            "generator_version": syn.get("generator_version", 1) if syn else None}
    meta.update(extra)
    return meta


def encode_events(src: str | Path, threshold: float | None = None, bin_ms: float = 5.0, prefer: str = "auto",
                  record_ms: float | None = None, progress=None) -> EncodedSet:
    """Binary event inputs (N, ceil(record/bin), 24) uint8 from published files (see module doc)."""
    from snncc.data.binning import bin_events, n_bins_for

    if not math.isfinite(bin_ms) or bin_ms <= 0:
        raise SnnccError(f"time_bin_size must be a positive number of ms, got {bin_ms}", field="--bin")
    events, labels, th, rec_ms, source = load_events(src, threshold, prefer, record_ms)
    if progress is not None:
        progress()
    n_bins = n_bins_for(rec_ms, bin_ms)
    try:
        inputs = bin_events(events, bin_ms, n_bins)
    except SnnccError as err:
        raise err.with_file(source)
    meta = _meta("events", source, th, bin_ms, bin_ms / 1000.0, n_bins,
                 {"record_ms": rec_ms, "events_before_binning": len(events),
                  "events_after_binning": int(inputs.sum())})
    return EncodedSet(inputs, labels, meta)


def load_raw_frames(src: str | Path, missing: str | None = None):
    """(raw-frame file, its ``RawSet``) for a directory of published files or the raw ``.pkl`` itself;
    ``missing`` is the rule stated when there is none (default: no raw-frame file here)."""
    from snncc.data import braille_files, formats

    src = Path(src)
    braille_files.require_exists(src)
    raw_path = braille_files.raw_file(src)
    if raw_path is None:
        raise SnnccError(missing or f"no {formats.RAW_NAME} here", file=str(src), field="path")
    return raw_path, formats.load_raw(raw_path)


def frame_set(src: str | Path) -> EncodedSet:
    """Inverted frames (N, T, 12) float32 (0 = rest, 255 = full load) for the LSTM."""
    raw_path, rs = load_raw_frames(src)
    inputs = rs.inverted().astype(np.float32)
    return EncodedSet(inputs, rs.labels, _meta("frames", str(raw_path), None, FRAME_MS, FRAME_MS / 1000.0,
                                               inputs.shape[1], {}))


def write_with_split(out: str | Path, encoded: EncodedSet, split_test: float | None = None, seed: int = 0) -> list[str]:
    """Write ``out`` (and ``OUT_train``/``OUT_test`` for a stratified ``split_test``); the paths written."""
    from snncc.data.dataset_file import save_dataset
    from snncc.data.split import stratified_split

    out = Path(out)
    inputs, labels, meta = encoded.inputs, encoded.labels, encoded.meta
    split = None
    if split_test is not None:
        try:
            parts = stratified_split(labels, seed=seed, test_fraction=split_test)
        except SnnccError as err:
            raise SnnccError(err.rule, field="--split-test") from None
        split = (parts.train, parts.test)
    save_dataset(out, inputs, labels, meta)
    written = [str(out)]
    if split is not None:
        for name, idx in zip(("train", "test"), split):
            p = out.with_name(f"{out.stem}_{name}{out.suffix or '.npz'}")
            save_dataset(p, inputs[idx], labels[idx], dict(meta, split=name, split_seed=seed,
                                                             split_test_fraction=split_test))
            written.append(str(p))
    return written
