"""The paper's encoding analysis and linear-SVM analyses (docs/braille.md; paper sections 3.1, 3.2.1).

Encoding table, per threshold th (events are counted per taxel and sample):

* ``events``           mean number of sigma-delta events;
* ``compression``      events(th = 1) / events(th)                       (gamma)
* ``mse``              mean over frames of (x - x_rec)^2, x_rec = x[0] + th * (#ON - #OFF so far)
* after binning with the paper's bin size for th (1: 5 ms, 2: 3, 5: 3, 10: 5): the same three
  numbers from the binary bins (a bin at ``b * bin`` ms counts at frame m if ``b*bin <= 25 m``),
  and ``lost`` = 1 - events after / events before;
* ``isi_below_1ms``     share of inter-spike intervals (per taxel and polarity) below 1 ms.

SVM analyses (scikit-learn): ``OneVsRestClassifier(LinearSVC(C=1))``, 5-fold stratified CV
(shuffled, seeded). Frame features are the inverted counts divided by the sensor's full scale 255
(a fixed, data-independent scale); "raw" = all T x 12 values, "time collapsed" = the mean over
frames per taxel; "PCA-12" = the first 12 principal components (fitted inside each fold) of the
first n frames; event features are the binary bins (all bins) or their sum per channel (spatial).
The calibration figures (several frame-SVM protocols, binning loss, short intervals, each beside
the paper's value) are in ``snncc.data.calibration``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from snncc.data.binning import bin_events, binned_reconstruction, n_bins_for, record_ms
from snncc.data.sigma_delta import Events, encode, isi_share_below, reconstruct

PAPER_BIN_MS = {1: 5, 2: 3, 5: 3, 10: 5}

# The paper's numbers (real recordings), for the side-by-side report.
PAPER = {
    "svm_raw": 86.7,
    "svm_collapsed": 72.3,
    "events": {1: 87.6, 2: 38.0, 5: 10.5, 10: 3.4},
    "compression": {1: 1.0, 2: 2.3, 5: 8.3, 10: 25.7},
    "mse": {1: 0.0, 2: 0.4, 5: 3.7, 10: 12.3},
    "events_binned": {1: 58.1, 2: 35.5, 5: 10.5, 10: 3.4},
    "compression_binned": {1: 1.5, 2: 2.5, 5: 8.3, 10: 25.7},
    "mse_binned": {1: 39.5, 2: 12.5, 5: 4.1, 10: 12.3},
    "isi_below_1ms_pct": {1: 8.22, 2: 0.45, 5: 0.0, 10: 0.0},
    "svm_events_all_bins": 58.9,
    "svm_events_spatial": 47.7,
}
Progress = Callable[[str], None]


@dataclass
class EncodingRow:
    threshold: float
    events: float
    compression: float
    mse: float
    bin_ms: float
    events_binned: float
    compression_binned: float
    mse_binned: float
    lost_pct: float
    isi_below_1ms_pct: float


@dataclass
class SvmResult:
    name: str
    mean_pct: float
    std_pct: float
    folds_pct: list[float] = field(default_factory=list)
    n_features: int = 0


def encoding_row(frames: np.ndarray, events: Events, threshold: float, bin_ms: float,
                 events_th1: float | None = None) -> EncodingRow:
    """One row of the encoding table from inverted frames (N, T, 12) and their events."""
    x = np.asarray(frames, dtype=np.float64)
    n, t, c = x.shape
    per = n * c
    ev = len(events) / per
    rec = reconstruct(events, x[:, 0, :], t, threshold)
    mse = float(np.mean((x - rec) ** 2))
    nb = n_bins_for(record_ms(t), bin_ms)
    binned = bin_events(events, bin_ms, nb)
    ev_b = float(binned.sum()) / per
    rec_b = binned_reconstruction(binned, x[:, 0, :], t, bin_ms, threshold)
    mse_b = float(np.mean((x - rec_b) ** 2))
    base = ev if events_th1 is None else events_th1
    isi, _ = isi_share_below(events, 1e-3)
    return EncodingRow(
        threshold=float(threshold), events=ev, compression=base / ev if ev else float("inf"),
        mse=mse, bin_ms=float(bin_ms), events_binned=ev_b,
        compression_binned=base / ev_b if ev_b else float("inf"), mse_binned=mse_b,
        lost_pct=100.0 * (1.0 - ev_b / ev) if ev else 0.0, isi_below_1ms_pct=100.0 * isi,
    )


def encoding_table(frames: np.ndarray, events_by_th: dict[float, Events],
                   bins: dict[float, float] | None = None) -> list[EncodingRow]:
    """Rows for every threshold (compression relative to the smallest threshold given, th 1)."""
    ths = sorted(events_by_th)
    base = len(events_by_th[ths[0]]) / (frames.shape[0] * frames.shape[2])
    rows = []
    for th in ths:
        b = (bins or {}).get(th, PAPER_BIN_MS.get(int(th), 5) if float(th).is_integer() else 5)
        rows.append(encoding_row(frames, events_by_th[th], th, b, base))
    return rows


def events_vs_bin_size(frames_shape: tuple[int, int, int], events_by_th: dict[float, Events],
                       bin_sizes: Sequence[float] = tuple(range(1, 11))) -> dict[float, dict[str, list]]:
    """Total events after binning per bin size, absolute and relative to 1 ms (paper Fig. 4a)."""
    _, t, _ = frames_shape
    out = {}
    for th, ev in sorted(events_by_th.items()):
        totals = [int(bin_events(ev, b, n_bins_for(record_ms(t), b)).sum()) for b in bin_sizes]
        ref = totals[0] if totals and totals[0] else 1
        out[th] = {"bin_ms": list(bin_sizes), "events": totals, "relative": [x / ref for x in totals],
                   "before_binning": len(ev)}
    return out


def _svm(C: float = 1.0):
    from sklearn.multiclass import OneVsRestClassifier
    from sklearn.svm import LinearSVC

    return OneVsRestClassifier(LinearSVC(C=C, dual="auto", max_iter=2000))


def svm_cv(name: str, X, y: np.ndarray, folds: int = 5, seed: int = 0, C: float = 1.0,
           pca: int | None = None, n_jobs: int | None = None) -> SvmResult:
    """Linear SVM (one-vs-rest) accuracy by stratified k-fold cross-validation, in percent."""
    from sklearn.decomposition import PCA
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.pipeline import make_pipeline

    counts = np.bincount(y)
    k = int(min(folds, counts[counts > 0].min()))
    if k < 2:
        return SvmResult(name, float("nan"), float("nan"), [], int(X.shape[1]))
    est = _svm(C)
    if pca is not None:
        est = make_pipeline(PCA(n_components=min(pca, X.shape[1]), random_state=seed), est)
    cv = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        scores = cross_val_score(est, X, y, cv=cv, n_jobs=n_jobs)
    return SvmResult(name, 100.0 * float(scores.mean()), 100.0 * float(scores.std()),
                     [100.0 * float(s) for s in scores], int(X.shape[1]))


def frame_features(frames: np.ndarray, kind: str, n_frames: int | None = None) -> np.ndarray:
    """SVM features from inverted frames: ``raw`` (all values) or ``collapsed`` (mean over time)."""
    x = np.asarray(frames, dtype=np.float64) / 255.0
    if n_frames is not None:
        x = x[:, :n_frames]
    if kind == "raw":
        return x.reshape(x.shape[0], -1)
    if kind == "collapsed":
        return x.mean(axis=1)
    raise ValueError(kind)


def svm_frames(frames: np.ndarray, labels: np.ndarray, seed: int = 0, n_jobs: int | None = None,
               progress: Progress | None = None) -> dict[str, SvmResult]:
    """The paper's two frame SVMs: all frames (raw) and time collapsed."""
    out = {}
    for kind in ("raw", "collapsed"):
        if progress:
            progress(f"SVM on {kind} frames")
        out[kind] = svm_cv(kind, frame_features(frames, kind), labels, seed=seed, n_jobs=n_jobs)
    return out


def svm_pca_vs_frames(frames: np.ndarray, labels: np.ndarray, frame_counts: Sequence[int],
                      seed: int = 0, n_jobs: int | None = None,
                      progress: Progress | None = None) -> list[dict]:
    """Accuracy with PCA-12 of the first n frames, for growing n (paper Fig. 6a)."""
    out = []
    for n in frame_counts:
        if progress:
            progress(f"PCA-12 SVM, first {n} frames")
        r = svm_cv(f"pca12_{n}", frame_features(frames, "raw", n), labels, seed=seed, pca=12,
                   n_jobs=n_jobs)
        out.append({"frames": int(n), "seconds": n / 40.0, "mean_pct": r.mean_pct, "std_pct": r.std_pct})
    return out


def svm_events(binned: np.ndarray, labels: np.ndarray, seed: int = 0, n_jobs: int | None = None,
               progress: Progress | None = None) -> dict[str, SvmResult]:
    """SVMs on binned events: all bins as predictors vs the sum per channel (spatial only)."""
    import scipy.sparse as sp

    n = binned.shape[0]
    if progress:
        progress("SVM on binned events (all bins)")
    all_bins = svm_cv("events_all_bins", sp.csr_matrix(binned.reshape(n, -1).astype(np.float64)),
                      labels, seed=seed, n_jobs=n_jobs)
    if progress:
        progress("SVM on event sums per channel")
    spatial = svm_cv("events_spatial", binned.sum(axis=1).astype(np.float64), labels, seed=seed,
                     n_jobs=n_jobs)
    return {"all_bins": all_bins, "spatial": spatial}


def encode_all(frames: np.ndarray, thresholds: Sequence[float]) -> dict[float, Events]:
    return {th: encode(frames, th) for th in thresholds}
