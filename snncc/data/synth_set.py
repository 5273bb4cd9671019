"""A synthetic Braille set on disk, in the published layout: raw frames, event files, generator record.

DIR/data_braille_letters_raw.pkl holds the raw 8-bit frames (255 at rest); each
DIR/data_braille_letters_th_<th>.pkl the sigma-delta events of the inverted frames ``255 - raw``
at threshold ``th``; DIR/SYNTHETIC.json the generator, its version, seed and parameters.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Callable, Sequence

GENERATOR = "snncc.data.synth (physical model, calibrated; see docs/braille_synthetic.md)"


def write_synthetic_set(out: str | Path, repetitions: int, seed: int, release: int, thresholds: Sequence[float],
                        version: int, on_frames: Callable[[int], None] | None = None,
                        on_file: Callable[[], None] | None = None) -> dict:
    """Generate 27 x ``repetitions`` samples and write them under ``out``; the summary record.

    ``mean_events_per_taxel[th]`` = events / (samples x taxels). ``on_frames(k)``: k samples
    generated so far; ``on_file()``: one more file written (1 + len(thresholds) in all).
    """
    import numpy as np

    from snncc.atomic import atomic_path
    from snncc.data import formats, synth
    from snncc.data.sigma_delta import encode
    from snncc.data.braille_files import MARKER
    from snncc.data.thresholds import threshold_key

    out = Path(out)
    tick = on_file or (lambda: None)
    raw, labels = synth.generate(repetitions, seed, progress=on_frames, version=version)
    formats.write_raw(out / formats.RAW_NAME, raw, labels, release=release)
    tick()
    x = 255 - raw.astype(np.int64)
    counts = {}
    for th in thresholds:
        ev = encode(x, th)
        counts[threshold_key(th)] = len(ev) / (raw.shape[0] * raw.shape[2])
        formats.write_events(out / formats.events_name(th), ev, labels, release=release)
        tick()
    info = {"synthetic": True, "generator": GENERATOR, "generator_version": version, "seed": seed,
            "repetitions": repetitions, "release": release, "samples": int(raw.shape[0]),
            "frames": int(raw.shape[1]), "thresholds": list(thresholds),
            "params": synth.params_dict(version=version)}
    with atomic_path(out / MARKER) as tmp:
        tmp.write_text(json.dumps(info, indent=2, sort_keys=True) + "\n")
    return {"out": str(out), "samples": int(raw.shape[0]), "frames": int(raw.shape[1]),
            "files": [formats.RAW_NAME] + [formats.events_name(t) for t in thresholds] + [MARKER],
            "mean_events_per_taxel": counts, "seed": seed, "release": release, "synthetic": True,
            "generator_version": version}
