"""Calibration figures of the SYNTHETIC Braille generator in one go (docs/braille_synthetic.md), written as JSON.

    python bench/studies/calibrate_synth.py                       # default set: 200 repetitions per letter
    python bench/studies/calibrate_synth.py --reps 20 --set force_sigma=0.3 --no-svm   # quick tuning loop

Generates the set in memory (generator version 2 unless --version 1), computes every figure of
``snncc.data.calibration`` (SVM protocols, event counts, binning loss, short intervals, event
SVMs) with the paper's value beside it, prints them and writes --out (JSON).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from snncc.data import synth  # noqa: E402
from snncc.data.calibration import calibration_figures  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=200, help="repetitions per letter (the default set: 200)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--version", type=int, default=synth.GENERATOR_VERSION)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a generator constant")
    ap.add_argument("--no-svm", action="store_true", help="event statistics only")
    ap.add_argument("--no-event-svm", action="store_true")
    ap.add_argument("--primary-only", action="store_true", help="frame SVMs under the primary protocol only")
    ap.add_argument("--protocols", default=None, help="comma-separated frame-SVM protocols (first = primary)")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", type=Path, default=None, help="JSON report")
    a = ap.parse_args(argv)
    params = synth.default_params(a.version)
    over = {}
    for kv in a.set:
        k, v = kv.split("=", 1)
        over[k] = type(getattr(params, k))(float(v)) if not isinstance(getattr(params, k), int) else int(v)
    params = dataclasses.replace(params, **over)
    t0 = time.perf_counter()
    raw, labels = synth.generate(a.reps, a.seed, params=params, version=a.version)
    t_gen = time.perf_counter() - t0
    x = 255 - raw.astype("int64")
    from snncc.data.calibration import FRAME_PROTOCOLS

    from snncc.data.calibration import PROTOCOLS_BY_NAME

    protos = FRAME_PROTOCOLS[:1] if a.primary_only else FRAME_PROTOCOLS
    if a.protocols:
        protos = tuple(PROTOCOLS_BY_NAME[k] for k in a.protocols.split(","))
    rep = calibration_figures(x, labels, seed=0, n_jobs=a.jobs, protocols=protos, svm=not a.no_svm,
                              event_svm=not a.no_event_svm and not a.no_svm)
    t_all = time.perf_counter() - t0
    print(rep.text())
    print(f"generated in {t_gen:.1f} s, total {t_all:.1f} s (shared CPU: timings noisy)")
    record = {"synthetic": True, "generator_version": a.version, "repetitions": a.reps, "seed": a.seed,
              "overrides": over, "seconds": t_all, **rep.as_dict()}
    if a.out:
        from snncc.atomic import atomic_path

        with atomic_path(a.out) as tmp:
            tmp.write_text(json.dumps(record, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
