"""Calibration of the synthetic generator at a reduced size (the full check is ``snncc data analyse``).

Event statistics are per taxel and sample, so they do not depend on the set size: the issue's
+-25 % tolerance applies unchanged. The SVM accuracies do depend on it: at 20 repetitions per
letter (540 samples, 16 training samples per letter and fold) instead of 200, seed 0 measures
about 41 % time-collapsed and 75 % raw, against 71.4 % / 87.5 % on the default set (paper: 72.3 /
86.7). The collapsed accuracy suffers most: with the fixed 1/255 feature scale, ``C = 1``
regularises its 12 small features strongly and fewer samples make that worse. So this test
checks the reduced-size values within +-8 points of what the reduced set gives, plus the paper's
qualitative finding (time matters: raw >> collapsed); the full-size numbers are in
docs/braille_synthetic.md.
"""

from __future__ import annotations

import numpy as np

from snncc.data.analysis import TARGETS, frame_features, svm_cv
from snncc.data.sigma_delta import encode
from snncc.data.synth import generate

REPS = 20


def test_reduced_calibration():
    raw, labels = generate(REPS, seed=0)
    x = 255 - raw.astype(np.int64)
    targets, rel = TARGETS["events"]
    for th, target in targets.items():
        per_taxel = len(encode(x, th)) / (x.shape[0] * x.shape[2])
        assert abs(per_taxel - target) <= rel * target, (th, per_taxel, target)
    collapsed = svm_cv("collapsed", frame_features(x, "collapsed"), labels, n_jobs=1).mean_pct
    raw_acc = svm_cv("raw", frame_features(x, "raw"), labels, n_jobs=1).mean_pct
    assert raw_acc > collapsed + 15  # the paper's finding: the temporal pattern carries information
    assert abs(collapsed - 41.0) <= 8.0, collapsed
    assert abs(raw_acc - 75.0) <= 8.0, raw_acc
