"""Figures of the encoding and SVM analyses (matplotlib, Agg backend, PNG files written atomically).

* ``reconstruction.png``: one taxel of one sample, original frames vs the reconstruction from
  events at every threshold, before (solid) and after (dashed) time binning (paper Figs. 3b, 4c);
* ``events_vs_bin_size.png``: total events after binning vs bin size, absolute and relative to
  1 ms (paper Fig. 4a);
* ``svm_vs_frames.png``: PCA-12 linear-SVM accuracy vs the number of frames used (paper Fig. 6a).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from snncc.atomic import atomic_path


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fig.savefig(fh, format="png", dpi=120, bbox_inches="tight", metadata={"Software": None})
    _plt().close(fig)
    return path


def reconstruction(path: str | os.PathLike, original: np.ndarray, curves: dict[float, tuple[np.ndarray, np.ndarray]],
                   title: str) -> Path:
    """``curves[th] = (before_binning, after_binning)``, each (T,) for one taxel."""
    plt = _plt()
    ths = sorted(curves)
    fig, axes = plt.subplots(len(ths), 1, figsize=(7, 1.9 * len(ths)), sharex=True, squeeze=False)
    t_ms = np.arange(original.shape[0]) * 25.0
    for ax, th in zip(axes[:, 0], ths):
        before, after = curves[th]
        ax.plot(t_ms, original, color="black", lw=1.5, label="frames")
        ax.step(t_ms, before, where="post", color="tab:blue", label="events")
        ax.step(t_ms, after, where="post", color="tab:orange", ls="--", label="binned events")
        ax.set_ylabel(f"th {th:g}")
    axes[0, 0].set_title(title)
    axes[0, 0].legend(loc="upper right", fontsize=7)
    axes[-1, 0].set_xlabel("time (ms)")
    return _save(fig, Path(path))


def events_vs_bin_size(path: str | os.PathLike, data: dict[float, dict]) -> Path:
    from snncc.log_axis import readable_log_axis

    plt = _plt()
    fig, (a, b) = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
    for th, d in sorted(data.items()):
        a.plot(d["bin_ms"], d["events"], marker="o", label=f"th {th:g}")
        b.plot(d["bin_ms"], [100 * r for r in d["relative"]], marker="o", label=f"th {th:g}")
    readable_log_axis(a, "y")
    a.set_ylabel("events after binning")
    b.set_ylabel("% of events at 1 ms")
    b.set_xlabel("time_bin_size (ms)")
    a.legend(fontsize=8)
    return _save(fig, Path(path))


def svm_vs_frames(path: str | os.PathLike, points: list[dict], raw_pct: float | None = None) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 3.5))
    s = [p["seconds"] for p in points]
    m = np.array([p["mean_pct"] for p in points])
    sd = np.array([p["std_pct"] for p in points])
    ax.plot(s, m, marker="o", label="PCA-12 + linear SVM")
    ax.fill_between(s, m - sd, m + sd, alpha=0.25)
    if raw_pct is not None:
        ax.axhline(raw_pct, color="gray", ls="--", label=f"all frames {raw_pct:.1f} %")
    ax.set_xlabel("frames used (s)")
    ax.set_ylabel("5-fold CV accuracy (%)")
    ax.legend(fontsize=8)
    return _save(fig, Path(path))
