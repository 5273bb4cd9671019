"""Time binning of events into the binary tensors the models eat, and input copies.

Rule (docs/braille.md, "Time bins and input channels"): with ``time_bin_size`` = ``bin_ms``::

    n_bins  = ceil(T_record_ms / bin_ms)            # T_record_ms = n_frames * 25 ms (1350 -> 270 at 5 ms)
    bin     = numpy.round(1000 * t / bin_ms)        # float64, round half to even (ties are common)
    channel = 2 * taxel + polarity                  # 0 = ON, 1 = OFF -> 24 channels
    X[sample, bin, channel] = 1                     # binary: several events in one bin count once

``tile_copies(x, k)`` repeats the 24 channels k times along the last axis, ``[c0..c23, c0..c23,
...]``, like the authors' ``inputs.tile((k,))``.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from snncc.data.letters import FRAME_RATE_HZ
from snncc.data.sigma_delta import Events
from snncc.errors import SnnccError


def record_ms(n_frames: int) -> Fraction:
    """Recording length in ms: ``n_frames / 40 Hz`` (54 frames -> 1350 ms)."""
    return Fraction(1000 * int(n_frames)) / Fraction(FRAME_RATE_HZ)


def n_bins_for(record_length_ms: float | Fraction, bin_ms: float) -> int:
    """``ceil(T_record / bin)`` computed exactly (1350 ms: 5 ms -> 270, 3 ms -> 450)."""
    if not np.isfinite(bin_ms) or bin_ms <= 0:
        raise SnnccError(f"time_bin_size must be a positive number of ms, got {bin_ms}",
                         field="time_bin_size")
    return int(math.ceil(Fraction(record_length_ms) / Fraction(bin_ms)))


def bin_index(times: np.ndarray, bin_ms: float) -> np.ndarray:
    """``numpy.round(1000 * t / bin_ms)`` as int64 (exactly the authors' float64 pipeline, docs/braille.md)."""
    t = np.asarray(times, dtype=np.float64)
    return np.round(1000 * t / bin_ms).astype(np.int64)


def bin_events(events: Events, bin_ms: float, n_bins: int) -> np.ndarray:
    """Binary event tensor (N, n_bins, 2*taxels) uint8, channel = 2*taxel + polarity."""
    if n_bins < 1:
        raise SnnccError(f"need at least one bin, got {n_bins}", field="time_bin_size")
    n_ch = 2 * events.n_taxels
    out = np.zeros((events.n_samples, n_bins, n_ch), dtype=np.uint8)
    if len(events) == 0:
        return out
    b = bin_index(events.times, bin_ms)
    bad = (b < 0) | (b >= n_bins)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise SnnccError(
            f"event at {events.times[i]:.6g} s falls in bin {b[i]}, outside 0..{n_bins - 1} "
            f"(record too short for these events? set the record length)",
            field=f"sample {int(events.sample[i])}.events",
        )
    ch = 2 * events.taxel + events.polarity.astype(np.int64)
    out[events.sample, b, ch] = 1
    return out


def binned_reconstruction(binned: np.ndarray, x0: np.ndarray, n_frames: int, bin_ms: float,
                          threshold: float) -> np.ndarray:
    """Frames rebuilt from binned events: ``x0 + th * (ON bins - OFF bins)`` with bin time ``b*bin``.

    A bin counts at frame ``m`` if ``b * bin_ms <= m * 25 ms``. Shape (N, n_frames, taxels).
    """
    n, n_bins, n_ch = binned.shape
    signed = binned[:, :, 0::2].astype(np.int64) - binned[:, :, 1::2].astype(np.int64)  # (N, B, C)
    b_ms = np.arange(n_bins, dtype=np.float64) * float(bin_ms)
    frame = np.ceil(b_ms / (1000.0 / FRAME_RATE_HZ) - 1e-9).astype(np.int64)  # first frame that sees bin b
    frame = np.clip(frame, 0, n_frames)
    per_frame = np.zeros((n, n_frames + 1, n_ch // 2), dtype=np.int64)
    np.add.at(per_frame, (slice(None), frame), signed)
    cum = np.cumsum(per_frame[:, :n_frames], axis=1)
    return np.asarray(x0, dtype=np.float64)[:, None, :] + float(threshold) * cum


def tile_copies(x, k: int):
    """``k`` identical copies of the channels along the last axis: ``[c0..c23, c0..c23, ...]``.

    Works on NumPy arrays and torch tensors (the authors' ``inputs.tile((k,))``).
    """
    k = int(k)
    if k < 1:
        raise SnnccError(f"nb_input_copies must be >= 1, got {k}", field="nb_input_copies")
    if isinstance(x, np.ndarray):
        return np.tile(x, (1,) * (x.ndim - 1) + (k,))
    return x.tile((1,) * (x.dim() - 1) + (k,))
