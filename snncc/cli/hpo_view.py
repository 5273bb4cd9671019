"""``snncc hpo run``'s progress: the search's ``StudyView`` drawn as two rich bars on stderr."""

from __future__ import annotations

from snncc.hpo.progress import StudyView


class RichStudyView(StudyView):
    """One bar for the study (trials spent of the budget), one for the running trial, and one
    line per finished or failed trial, on ``console``; a fresh pair of bars per study."""

    def __init__(self, console):
        self.console = console
        self.progress = None
        self.study_task = self.trial_task = None

    def study_start(self, study: str) -> None:
        from snncc.cli.output import bar_columns
        from rich.progress import Progress

        self.close()
        self.progress = Progress(*bar_columns(), console=self.console, transient=False)
        self.study_task = self.progress.add_task(f"study {study}", total=None)
        self.trial_task = None
        self.progress.start()

    def study_update(self, budget) -> None:
        if self.progress is not None:
            self.progress.update(self.study_task, total=budget.n_trials, completed=min(budget.spent, budget.n_trials),
                                 description=f"study: {budget.complete} complete, {budget.pruned} pruned, "
                                             f"{budget.running} running")

    def waiting(self, budget) -> None:
        if self.progress is not None:
            self.progress.update(self.study_task, description=f"study: waiting for {budget.running} running "
                                                              "trial(s) (other workers, or stale ones to be re-queued)")

    def trial_start(self, number: int, epochs: int, params: dict) -> None:
        if self.progress is None:
            return
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
        from snncc.hpo.hardware import hardware_summary

        if self.trial_task is not None:
            self.progress.update(self.trial_task, advance=1, description=f"trial {number}: done")
        figures = hardware_summary(outcome.hardware, outcome.target)     # headed as the target's report columns
        self.console.print(f"trial {number}: accuracy {100 * outcome.accuracy:.2f} % ({outcome.selected_on})"
                           + (f"; {outcome.target}: {figures}" if figures else ""))

    def trial_error(self, number: int, line: str) -> None:
        self.console.print(f"trial {number} failed: {line}")

    def close(self) -> None:
        if self.progress is not None:
            self.progress.stop()
            self.progress = None
            self.study_task = self.trial_task = None
