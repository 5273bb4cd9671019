"""Progress of a search: one bar for the study (trials spent of the budget), one for the running trial."""

from __future__ import annotations


class StudyView:
    """Callbacks the search calls; this base class shows nothing (``--quiet``, tests)."""

    def study_update(self, budget) -> None: ...
    def waiting(self, budget) -> None: ...
    def trial_start(self, number: int, epochs: int, params: dict) -> None: ...
    def trial_epoch(self, record, metric: float) -> None: ...
    def trial_phase(self, text: str) -> None: ...
    def trial_done(self, number: int, outcome) -> None: ...
    def trial_error(self, number: int, line: str) -> None: ...
    def close(self) -> None: ...


class RichStudyView(StudyView):
    """Two rich progress bars on stderr and one line per finished trial."""

    def __init__(self, study: str, console):
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        self.console = console
        self.progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), console=console, transient=False)
        self.study_task = self.progress.add_task(f"study {study}", total=None)
        self.trial_task = None
        self.progress.start()

    def study_update(self, budget) -> None:
        self.progress.update(self.study_task, total=budget.n_trials, completed=min(budget.spent, budget.n_trials),
                             description=f"study: {budget.complete} complete, {budget.pruned} pruned, "
                                         f"{budget.running} running")

    def waiting(self, budget) -> None:
        self.progress.update(self.study_task, description=f"study: waiting for {budget.running} running trial(s) "
                                                          "(other workers, or stale ones to be re-queued)")

    def trial_start(self, number: int, epochs: int, params: dict) -> None:
        if self.trial_task is not None:
            self.progress.remove_task(self.trial_task)
        self.trial_task = self.progress.add_task(f"trial {number}", total=epochs + 1)

    def trial_epoch(self, record, metric: float) -> None:
        if self.trial_task is not None:
            self.progress.update(self.trial_task, advance=1,
                                 description=f"trial: epoch {record.epoch}, accuracy {100 * metric:.1f} %")

    def trial_phase(self, text: str) -> None:
        if self.trial_task is not None:
            self.progress.update(self.trial_task, description=f"trial: {text}")

    def trial_done(self, number: int, outcome) -> None:
        hw = outcome.hardware or {}
        if self.trial_task is not None:
            self.progress.update(self.trial_task, advance=1, description=f"trial {number}: done")
        self.console.print(f"trial {number}: accuracy {100 * outcome.accuracy:.2f} % ({outcome.selected_on}), "
                           f"{hw.get('cores')} cores, {hw.get('synaptic_ops_per_sample', 0):,.0f} synops/sample, "
                           f"{hw.get('energy_uj_per_sample', 0):.3g} uJ/sample (ESTIMATE)")

    def trial_error(self, number: int, line: str) -> None:
        self.console.print(f"trial {number} failed: {line}")

    def close(self) -> None:
        self.progress.stop()
