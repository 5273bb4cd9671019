"""The whole ``snncc data analyse`` report: encoding table, SVMs and the paper's figures of one data set.

Events per threshold come from the directory's event file when there is one (it must hold the
raw file's samples and letters), else from encoding the raw frames. The encoding table uses the
paper's bin size per threshold (``analysis.PAPER_BIN_MS``, 5 ms otherwise); the frame and event
SVMs are those of ``snncc.data.calibration`` (the paper's protocols) unless the event SVMs ask
for another threshold or bin, which are then run with ``analysis.svm_events``.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Sequence

import numpy as np

from snncc.errors import SnnccError


def _counter(progress, total: int):
    """(note(text), advance(k)) reporting ``progress(done, total, phase)``: note names the phase
    (first "analysing"), advance adds k steps done (None: no-ops)."""
    if progress is None:
        return (lambda _text: None), (lambda _k=1: None)
    state = {"done": 0, "phase": "analysing"}

    def note(text: str) -> None:
        state["phase"] = text
        progress(state["done"], total, text)

    def advance(k: int = 1) -> None:
        state["done"] = min(total, state["done"] + k)
        progress(state["done"], total, state["phase"])

    return note, advance


def paper_bin_ms(th: float) -> float:
    """The paper's bin size for threshold ``th`` (5 ms for thresholds it does not use)."""
    from snncc.data.analysis import PAPER_BIN_MS

    return PAPER_BIN_MS.get(int(th), 5) if float(th).is_integer() else 5


def _events_by_threshold(src: Path, x: np.ndarray, labels: np.ndarray, ths: Sequence[float], note, advance):
    """{th: Events} and {th key: where they came from}."""
    from snncc.data import braille_files, formats
    from snncc.data.sigma_delta import encode
    from snncc.data.thresholds import threshold_key

    events_by_th, from_files = {}, {}
    for th in ths:
        note(f"events th {th:g}")
        p = braille_files.events_file(src, th) if src.is_dir() else None
        if p is not None:
            es = formats.load_events(p)
            if es.events.n_samples != x.shape[0] or not np.array_equal(es.labels, labels):
                raise SnnccError("samples or letters differ from the raw-frame file", file=str(p), field="letter")
            events_by_th[th] = es.events
            from_files[threshold_key(th)] = str(p)
        else:
            events_by_th[th] = encode(x, th)
            from_files[threshold_key(th)] = "encoded from raw frames"
        advance()
    return events_by_th, from_files


def _figures(out: Path, x: np.ndarray, labels: np.ndarray, ths, events_by_th, vs_bin, pca_points, svm_res) -> list[str]:
    """The reconstruction, events-vs-bin-size and (with PCA points) SVM-vs-frames figures."""
    from snncc.data import figures as figs
    from snncc.data.binning import bin_events, binned_reconstruction, n_bins_for, record_ms
    from snncc.data.letters import CLASSES
    from snncc.data.sigma_delta import reconstruct

    n, t, _ = x.shape
    i, k = 0, 1
    if n:
        # the sample/taxel with the most activity at the first threshold shows the encoding best
        counts = events_by_th[ths[0]].counts()
        i, k = np.unravel_index(int(np.argmax(counts)), counts.shape)
    curves = {}
    for th in ths:
        ev = events_by_th[th].select(np.array([i]))
        before = reconstruct(ev, x[i:i + 1, 0, :], t, th)[0, :, k]
        b = paper_bin_ms(th)
        bb = bin_events(ev, b, n_bins_for(record_ms(t), b))
        after = binned_reconstruction(bb, x[i:i + 1, 0, :], t, b, th)[0, :, k]
        curves[th] = (before, after)
    written = [str(figs.reconstruction(out / "reconstruction.png", x[i, :, k], curves,
                                       f"sample {i} ('{CLASSES[labels[i]]}'), taxel {k}")),
               str(figs.events_vs_bin_size(out / "events_vs_bin_size.png", vs_bin))]
    if pca_points:
        written.append(str(figs.svm_vs_frames(out / "svm_vs_frames.png", pca_points,
                                              svm_res["raw"].mean_pct if "raw" in svm_res else None)))
    return written


def analyse_braille(src: str | Path, thresholds: Sequence[float] = (1, 2, 5, 10), svm: bool = True,
                    pca_step: int = 6, event_svm: bool = True, event_threshold: float = 1.0,
                    event_bin: float = 5.0, seed: int = 0, jobs: int = 2, figures: str | Path | None = None,
                    progress=None) -> dict:
    """The report of ``snncc data analyse`` (see the module doc) as a plain dict.

    ``pca_step``: a PCA-12 SVM every N frames (0: none); ``figures``: a directory to write the
    PNG figures into; ``progress``: ``progress(done, total, phase)`` over the steps (None: none).
    """
    from snncc.data import analysis, braille_files, calibration, formats
    from snncc.data.binning import bin_events, n_bins_for, record_ms
    from snncc.data.encoding import load_raw_frames
    from snncc.data.sigma_delta import encode
    from snncc.data.thresholds import threshold_key

    src = Path(src)
    ths = list(thresholds)
    raw_path, rs = load_raw_frames(src, f"the analysis needs the raw frames ({formats.RAW_NAME})")
    x = rs.inverted()
    labels = rs.labels
    n, t, c = x.shape
    syn = braille_files.synthetic_info(raw_path)
    frame_counts = sorted(set(list(range(1, t + 1, pca_step)) + [t])) if pca_step else []
    steps = len(ths) * 2 + (2 if svm else 0) + (2 if event_svm else 0) + len(frame_counts)
    note, advance = _counter(progress, steps)

    events_by_th, from_files = _events_by_threshold(src, x, labels, ths, note, advance)
    note("encoding table")
    rows = []
    base = len(events_by_th[ths[0]]) / (n * c)
    for th in ths:
        try:
            rows.append(analysis.encoding_row(x, events_by_th[th], th, paper_bin_ms(th), base))
        except SnnccError as err:
            raise err.with_file(from_files[threshold_key(th)])
        advance()
    vs_bin = analysis.events_vs_bin_size(x.shape, events_by_th)
    std_events = event_threshold == 1 and event_bin == 5
    note("the paper's figures: frame SVMs under each protocol, event statistics")
    paper_figs = calibration.calibration_figures(x, labels, seed=seed, n_jobs=jobs, svm=svm,
                                                 event_svm=event_svm and std_events, progress=note)
    svm_res = paper_figs.svm_results() if svm else {}
    advance(2 if svm else 0)
    pca_points = []
    for k in frame_counts:
        note(f"PCA-12 SVM, first {k} frames")
        pca_points += analysis.svm_pca_vs_frames(x, labels, [k], seed=seed, n_jobs=jobs)
        advance()
    ev_svm = paper_figs.event_svm_results() if event_svm and std_events else {}
    if event_svm and not std_events:
        ev = events_by_th.get(event_threshold)
        if ev is None:
            ev = encode(x, event_threshold)
        binned = bin_events(ev, event_bin, n_bins_for(record_ms(t), event_bin))
        note("SVM, binned events")
        ev_svm = analysis.svm_events(binned, labels, seed=seed, n_jobs=jobs)
        advance(2)
    calib_note = None
    if syn and n < 27 * 200:
        calib_note = (f"the targets refer to the default set (200 repetitions per letter); with {n} samples "
                      "the SVM accuracies are lower (fewer training samples), the event counts are not")
    fig_files = ([] if figures is None else
                 _figures(Path(figures), x, labels, ths, events_by_th, vs_bin, pca_points, svm_res))
    return {
        "source": str(src), "samples": n, "frames": t, "taxels": c, "synthetic": syn is not None,
        "events_from": from_files,
        "encoding": [asdict(r) for r in rows],
        "events_vs_bin_size": {threshold_key(k): v for k, v in vs_bin.items()},
        "svm_frames": {k: asdict(v) for k, v in svm_res.items()},
        "svm_pca_vs_frames": pca_points,
        "svm_events": ({"threshold": event_threshold, "bin_ms": event_bin,
                        **{k: asdict(v) for k, v in ev_svm.items()}} if ev_svm else {}),
        "paper": analysis.PAPER,
        "paper_figures": paper_figs.as_dict(),
        "calibration": [f.as_dict() for f in paper_figs.figures] if syn else [],
        "calibration_note": calib_note,
        "figures": fig_files,
    }
