"""``snncc hpo run|report|space`` as functions: the paper's two-step search, its report, its search space."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping, Sequence

from snncc.targets import DEFAULT_TARGET
from snncc.errors import one_line

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.hpo.progress import StudyView
    from snncc.hpo.report import HpoReport
    from snncc.hpo.space import Range
    from snncc.hpo.study import RunSummary
    from snncc.frontends.params import PaperParams

SPACE_NOTE = "ranges are snncc's choice; the paper lists the hyper-parameters, not their ranges"


@dataclass
class HpoRunResult:
    """``summaries``: one ``RunSummary`` per step run (study, step, created, budget, trials_run_here,
    notes); ``report_command``: the ``snncc hpo report`` line for the last study."""

    summaries: list[RunSummary]
    report_command: str

    def as_dict(self) -> list:
        """What ``snncc hpo run --json`` prints: the list of the steps' summaries."""
        from snncc.records import to_jsonable

        return to_jsonable(self.summaries)

    def render_text(self, console: Console) -> None:
        for s in self.summaries:
            b = s.budget
            console.print(f"study {s.study} ({s.step}): {b['complete']} complete, {b['pruned']} pruned, "
                          f"{b['failed']} failed of {b['n_trials']}; {len(s.trials_run_here)} run by this worker")
            for note in s.notes:
                console.print(f"note: {note}")
        console.print(f"report: {one_line(self.report_command)}", markup=False)


def hpo_run(name: str, *, data: str | os.PathLike, threshold: int = 1, step: str = "both", trials: int = 600,
            restarts: int = 2, grid_span: int = 1, objectives: str | Sequence[str] = "accuracy",
            ranges: Sequence[str] | None = None, model: str = "rsnn", epochs: int = 300, subset: int | None = None,
            seed: int = 0, val_fraction: float = 0.2, select: str = "val", hidden: int | None = None,
            batch_size: int = 128, energy_samples: int = 16, emulate: int = 0, pruner: str = "median",
            startup: int = 3, preset: bool = True, storage: str | None = None, workdir: str | os.PathLike = "hpo",
            device: str = "auto", threads: int = 1, heartbeat: int = 30, target: str = DEFAULT_TARGET,
            target_options: Mapping[str, object] | None = None, view: StudyView | None = None) -> HpoRunResult:
    """Run or resume the search ``name`` (step 2's study is NAME-grid) in this worker (see docs/hpo.md).

    ``objectives``: a comma list or sequence (``pareto`` = accuracy,energy,cores); ``ranges``:
    ``KEY=LOW:HIGH`` / ``KEY=VALUE`` overrides (``--range``); ``workdir`` is ``--dir``;
    ``storage`` an Optuna URL (default: SQLite in ``workdir``); ``target``: whose ``hardware`` capability
    costs each trial (its objectives are the hardware objectives ``objectives`` may name);
    ``target_options``: that target's ``lower`` options each trial compiles with, as ``snncc compile``'s
    keywords (e.g. ``{"allow_reset_change": True}`` for Xylo, whose chip cannot reset to zero), stored with
    the study's plan. ``view``: the search's progress
    callbacks, a ``snncc.hpo.progress.StudyView`` (study_start, study_update, waiting,
    trial_start, trial_epoch, trial_phase, trial_done, trial_error, close; the CLI draws them as
    rich bars); None: silent. Ctrl-C re-queues the running trial and raises
    ``snncc.hpo.study.Interrupted``.
    """
    from snncc.targets import get_target, verb_options

    given = {k: v for k, v in (target_options or {}).items() if v is not None and v is not False}
    verb_options(get_target(target), given, "lower")   # validated first, whether or not a trial compiles with them
    import torch

    from snncc.errors import SnnccError
    from snncc.hpo.outcome import parse_objectives
    from snncc.hpo.run import HpoRequest, run_hpo
    from snncc.hpo.storage import report_command

    if threads < 1:
        raise SnnccError("must be >= 1", field="--threads")
    if batch_size < 1:
        raise SnnccError("must be >= 1", field="--batch-size")
    if not isinstance(objectives, str):
        objectives = ",".join(objectives)
    req = HpoRequest(name=name, data=str(data), threshold=threshold, step=step, trials=trials, restarts=restarts,
                     grid_span=grid_span, objectives=parse_objectives(objectives, target), ranges=list(ranges or []),
                     kind=model, epochs=epochs, subset=subset, seed=seed, val_fraction=val_fraction, select=select,
                     batch_size=batch_size, n_hidden=hidden, energy_samples=energy_samples, emulate_samples=emulate,
                     pruner=pruner, n_startup=startup, enqueue_preset=preset, storage=storage, workdir=str(workdir),
                     device=device, heartbeat=heartbeat, target=target,
                     target_options=given)
    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        summaries = run_hpo(req, view)
    finally:
        torch.set_num_threads(before)
    return HpoRunResult(summaries, report_command(summaries[-1].study, storage, os.fspath(workdir)))


@dataclass
class HpoReportResult:
    """``report``: the ``HpoReport`` (study, storage, plan, counts, rows, best, front, paper_presets,
    synthetic_data, notes); ``figure``: the front figure written (or None)."""

    report: HpoReport
    figure: str | None = None

    def as_dict(self) -> dict:
        """What ``snncc hpo report --json`` prints: the report and the figure."""
        from snncc.records import to_jsonable

        return to_jsonable({**self.report.as_dict(), "figure": self.figure})

    def render_text(self, console: Console) -> None:
        self.report.render_text(console)
        if self.figure:
            console.print(f"wrote {one_line(self.figure)}", markup=False)


def hpo_report(study: str, *, storage: str | None = None, workdir: str | os.PathLike = "hpo",
               output: str | os.PathLike | None = None, no_plot: bool = False) -> HpoReportResult:
    """Best trials per objective, the Pareto front (accuracy, energy, cores) and the paper's presets of
    ``study`` in ``storage`` (default: the SQLite file in ``workdir``); the front figure into
    ``output`` (default WORKDIR/STUDY-front.png) unless ``no_plot``."""
    from pathlib import Path

    from snncc.atomic import protecting
    from snncc.errors import SnnccError
    from snncc.hpo.report import study_report
    from snncc.hpo.storage import open_storage, redact, sqlite_file, study_storage_url

    url = study_storage_url(storage, os.fspath(workdir), must_exist=True)
    database = sqlite_file(url)
    if database is not None and not database.is_file():   # reading must not create an empty database
        raise SnnccError("no study storage here (no such SQLite file)", file=str(database), field="--storage")
    report = study_report(open_storage(url), study, redact(url))
    with protecting([database] if database is not None else []):   # the study's storage is an input
        written = None if no_plot else report.plot(Path(output) if output else Path(workdir) / f"{study}-front.png")
    return HpoReportResult(report, str(written) if written else None)


@dataclass
class HpoSpaceResult:
    """``space``: hyper-parameter -> ``Range`` (low, high, log, integer); ``paper_presets``:
    threshold -> the paper's ``PaperParams``; ``note``: where the ranges come from."""

    space: dict[str, Range]
    paper_presets: dict[int, PaperParams]
    note: str = SPACE_NOTE

    def as_dict(self) -> dict:
        """What ``snncc hpo space --json`` prints."""
        from snncc.records import to_jsonable

        return to_jsonable({"space": {k: r.as_dict() for k, r in self.space.items()},
                            "paper_presets": {th: p.as_dict() for th, p in self.paper_presets.items()},
                            "note": self.note})

    def render_text(self, console: Console) -> None:
        from rich.table import Table

        t = Table(title="search space (ranges: snncc's choice; the paper gives none) and the paper's presets")
        for col in ("hyper-parameter", "low", "high", "scale", *[f"th {th}" for th in self.paper_presets]):
            t.add_column(col, justify="right")
        for k, r in self.space.items():
            t.add_row(k, f"{r.low:g}", f"{r.high:g}", ("log" if r.log else "linear") + (", int" if r.integer else ""),
                      *[f"{getattr(p, k):g}" for p in self.paper_presets.values()])
        console.print(t)


def hpo_space() -> HpoSpaceResult:
    """The search space (snncc's ranges) beside the paper's four presets."""
    from snncc.hpo.space import SEARCH_SPACE
    from snncc.training.presets import PRESETS

    return HpoSpaceResult(dict(SEARCH_SPACE), dict(PRESETS))
