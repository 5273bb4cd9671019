"""``snncc data analyse`` as a function: the paper's encoding table and linear-SVM analyses of a data set."""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Iterable

from snncc.verbs import VerbProgress

if TYPE_CHECKING:
    from rich.console import Console


@dataclass
class AnalysisResult:
    """The report (``snncc.data.analysis_report``): ``source``, ``samples``, ``frames``, ``taxels``,
    ``synthetic``, ``events_from`` (file or "encoded from raw frames" per threshold), ``encoding``
    (one row per threshold), ``events_vs_bin_size``, ``svm_frames``, ``svm_pca_vs_frames``,
    ``svm_events``, ``paper`` (the paper's values), ``paper_figures`` (measured vs paper),
    ``calibration``, ``calibration_note``, ``figures`` (files written)."""

    source: str
    samples: int
    frames: int
    taxels: int
    synthetic: bool
    events_from: dict
    encoding: list
    events_vs_bin_size: dict
    svm_frames: dict
    svm_pca_vs_frames: list
    svm_events: dict
    paper: dict
    paper_figures: dict
    calibration: list
    calibration_note: str | None
    figures: list

    def as_dict(self) -> dict:
        """What ``snncc data analyse --json`` prints."""
        from snncc.records import to_jsonable

        return to_jsonable(asdict(self))

    def render_text(self, console: Console) -> None:
        from snncc.data.analysis_text import render_analysis

        render_analysis(asdict(self), console)


def data_analyse(src: str | os.PathLike, *, figures: str | os.PathLike | None = None,
                 thresholds: str | Iterable[float] = "1,2,5,10", svm: bool = True, pca_step: int = 6,
                 event_svm: bool = True, event_threshold: float = 1.0, event_bin: float = 5.0, seed: int = 0,
                 jobs: int = 2, progress: VerbProgress | None = None) -> AnalysisResult:
    """Analyse ``src`` (a directory of published files; raw frames required): encoding per
    threshold, frame SVMs (``svm``), PCA-12 SVM every ``pca_step`` frames (0: none), binned-event
    SVMs (``event_svm`` at ``event_threshold`` / ``event_bin`` ms), the paper's figures; PNG figures
    into ``figures``. ``progress``: ``progress(done, total, phase)`` over the steps, the phase naming
    the one running (None: none)."""
    from pathlib import Path

    from snncc.data.analysis_report import analyse_braille
    from snncc.data.thresholds import parse_thresholds
    from snncc.errors import SnnccError

    if pca_step < 0:
        raise SnnccError("must be >= 0", field="--pca-step")
    if jobs < 1:
        raise SnnccError("must be >= 1", field="--jobs")
    report = analyse_braille(Path(src), parse_thresholds(thresholds), svm=svm, pca_step=pca_step,
                             event_svm=event_svm, event_threshold=event_threshold, event_bin=event_bin, seed=seed,
                             jobs=jobs, figures=None if figures is None else Path(figures), progress=progress)
    return AnalysisResult(**report)
