"""The paper's two-step search as Optuna studies: step 1 annealing, step 2 a grid; resumable.

A study is named and lives in a storage (``storage.py``). Its plan (``StudyPlan``) is stored with
it when it is created; rerunning the same command loads it and continues: finished trials
(COMPLETE, PRUNED, or FAIL with an error) are never run again, a trial left RUNNING by a killed
worker is marked FAIL once its heartbeat is stale and its parameters are queued again, and a
trial interrupted by Ctrl-C is marked FAIL and queued again at once. Each worker starts trials
while ``spent + running + waiting < n_trials`` and then waits for the running ones, so several
workers (processes or machines on one storage) share one budget. Two workers whose checks race can
create one trial too many; trial numbers are unique, so the trial that finds ``n_trials`` counted
trials below its number is cancelled before training (FAIL, user attribute ``over_budget``, not
counted) and the study ends with exactly ``n_trials``.
"""

from __future__ import annotations

import os
import socket
import time
import warnings
from dataclasses import asdict, dataclass, field, fields
from typing import Callable

from snncc.targets import DEFAULT_TARGET
from snncc.errors import SnnccError
from snncc.hpo.outcome import TrialOutcome, directions
from snncc.hpo.space import GRID_KEYS, Range, grid_around, preset_in_space, space_from_dict

STEPS = ("anneal", "grid")
SELECT = ("val", "test")
PLAN_ATTR = "snncc_plan"
INTERRUPTED_ATTR = "snncc_interrupted"
OVER_BUDGET_ATTR = "over_budget"     # a trial two workers' racing checks started beyond the budget: cancelled


@dataclass
class StudyPlan:
    """What defines a study (stored with it; a rerun must ask for the same, except a larger budget)."""

    name: str
    step: str                         # "anneal" | "grid"
    data: str
    threshold: int
    objectives: tuple = ("accuracy",)
    n_trials: int = 600               # the paper: 600 (anneal); grid: its size
    space: dict = field(default_factory=dict)       # name -> Range.as_dict()
    fixed: dict = field(default_factory=dict)       # grid: step 1's best for the other seven
    grid: dict | None = None                        # grid: time_bin_size, nb_input_copies values
    restarts: tuple = ()                            # anneal: trial numbers of the re-initialisations
    kind: str = "rsnn"
    epochs: int = 300
    subset: int | None = None
    seed: int = 0
    val_fraction: float = 0.2
    select: str = "val"               # "val" | "test" (the paper's, optimistic)
    batch_size: int = 128
    n_hidden: int | None = None       # None: the paper's 450
    order: str = "spytorch"
    energy_samples: int = 16
    emulate_samples: int = 0
    pruner: str = "median"            # "median" | "none" (single objective only)
    n_startup: int = 3                # anneal: prior draws after each (re)initialisation
    enqueue_preset: bool = True       # anneal: the paper's preset for the threshold as trial 0
    from_study: str | None = None     # grid: the step-1 study it is centred on
    target: str = DEFAULT_TARGET             # whose ``hardware`` capability costs each trial (its objectives)
    target_options: dict = field(default_factory=dict)   # the target's lower options each trial compiles with

    # fields a rerun may change without changing the study
    RUNTIME = ("n_trials",)

    def as_dict(self) -> dict:
        d = asdict(self)
        d["objectives"] = list(self.objectives)
        d["restarts"] = list(self.restarts)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "StudyPlan":
        known = {f.name for f in fields(cls)}
        d = {k: v for k, v in d.items() if k in known}
        d["objectives"] = tuple(d.get("objectives", ("accuracy",)))
        d["restarts"] = tuple(d.get("restarts", ()))
        return cls(**d)

    @property
    def directions(self) -> list[str]:
        known = directions(self.target)
        return [known[o] for o in self.objectives]

    @property
    def ranges(self) -> dict[str, Range]:
        return space_from_dict(self.space)

    def check(self) -> None:
        if self.step not in STEPS:
            raise SnnccError(f"unknown step {self.step!r} (known: {', '.join(STEPS)})", field="--step")
        if self.select not in SELECT:
            raise SnnccError("must be val or test", field="--select")
        if self.n_trials < 1:
            raise SnnccError("must be >= 1", field="--trials")
        if self.epochs < 1:
            raise SnnccError("must be >= 1", field="--epochs")
        if self.select == "val" and not 0 < self.val_fraction < 0.8:
            raise SnnccError("validation selection needs 0 < --val-fraction < 0.8", field="--val-fraction")
        if self.n_hidden is not None and self.n_hidden < 1:
            raise SnnccError("must be >= 1", field="--hidden")
        if self.energy_samples < 1 or self.emulate_samples < 0:
            raise SnnccError("need --energy-samples >= 1 and --emulate >= 0", field="--energy-samples")
        if "emulated_accuracy" in self.objectives and self.emulate_samples < 1:
            raise SnnccError("objective emulated_accuracy needs --emulate N (N > 0)", field="--objectives")
        if self.pruner not in ("median", "none"):
            raise SnnccError("must be median or none", field="--pruner")
        if self.target_options:
            from snncc.targets import get_target
            from snncc.targets.base import target_options

            target_options(get_target(self.target), self.target_options, "lower")   # refuses what it does not take
        if self.kind not in ("rsnn", "ffsnn"):
            raise SnnccError("the search trains spiking models: rsnn or ffsnn", field="--model")

    def differences(self, other: "StudyPlan") -> list[str]:
        a, b = self.as_dict(), other.as_dict()
        return [k for k in a if k not in self.RUNTIME and k != "restarts" and a[k] != b.get(k)]


@dataclass
class Budget:
    """Trial counts of a study against its budget (see the module doc)."""

    complete: int
    pruned: int
    failed: int                       # failed with an error (spent, not retried)
    retried: int                      # failed by a kill or Ctrl-C and queued again
    running: int
    waiting: int
    n_trials: int
    cancelled: int = 0                # over-budget trials cancelled before training (not counted)

    @property
    def spent(self) -> int:
        return self.complete + self.pruned + self.failed

    @property
    def done(self) -> bool:
        return self.spent >= self.n_trials and self.waiting == 0 and self.running == 0

    @property
    def may_start(self) -> bool:
        return self.waiting > 0 or self.spent + self.running + self.waiting < self.n_trials


def retried_numbers(trials) -> set[int]:
    """Numbers of failed trials whose parameters were queued again (a retry names them)."""
    out: set[int] = set()
    for t in trials:
        out.update(int(n) for n in t.system_attrs.get("retry_history", []))
        if "failed_trial" in t.system_attrs:
            out.add(int(t.system_attrs["failed_trial"]))
    return out


def counted(trials) -> list:
    """The trials that use the budget: all but re-queued failures and cancelled over-budget trials."""
    from optuna.trial import TrialState

    retried = retried_numbers(trials)
    return [t for t in trials if not t.user_attrs.get(OVER_BUDGET_ATTR)
            and not (t.state == TrialState.FAIL and t.number in retried)]


def over_budget(study, number: int, n_trials: int) -> bool:
    """Trial ``number`` started although ``n_trials`` counted trials with smaller numbers exist."""
    return sum(t.number < number for t in counted(study.get_trials(deepcopy=False))) >= n_trials


def budget(study, n_trials: int) -> Budget:
    from optuna.trial import TrialState

    trials = study.get_trials(deepcopy=False)
    used = counted(trials)
    count = {s: 0 for s in TrialState}
    for t in used:
        count[t.state] += 1
    cancelled = sum(bool(t.user_attrs.get(OVER_BUDGET_ATTR)) for t in trials)
    fails = sum(t.state == TrialState.FAIL for t in trials)
    return Budget(count[TrialState.COMPLETE], count[TrialState.PRUNED], count[TrialState.FAIL],
                  fails - count[TrialState.FAIL] - cancelled, count[TrialState.RUNNING],
                  count[TrialState.WAITING], n_trials, cancelled)


# --------------------------------------------------------------------------- opening a study

def _sampler(plan: StudyPlan):
    import optuna

    from snncc.hpo.annealing import AnnealingSampler

    if plan.step == "grid":
        return optuna.samplers.GridSampler(plan.grid, seed=plan.seed)
    return AnnealingSampler(restarts=plan.restarts, n_startup=plan.n_startup, seed=plan.seed)


def _pruner(plan: StudyPlan):
    import optuna

    if plan.pruner == "none" or len(plan.objectives) > 1:
        return optuna.pruners.NopPruner()
    return optuna.pruners.MedianPruner(n_startup_trials=max(1, plan.n_startup), n_warmup_steps=max(1, plan.epochs // 10))


def stored_plan(study) -> StudyPlan | None:
    d = study.user_attrs.get(PLAN_ATTR)
    return StudyPlan.from_dict(d) if d else None


def open_study(plan: StudyPlan, storage, on_create: Callable | None = None):
    """(study, created): create ``plan``'s study, or load it and check it is the same study."""
    import optuna

    plan.check()
    created = False
    try:
        study = optuna.create_study(study_name=plan.name, storage=storage, directions=plan.directions,
                                    sampler=_sampler(plan), pruner=_pruner(plan), load_if_exists=False)
        study.set_user_attr(PLAN_ATTR, plan.as_dict())
        created = True
        if on_create is not None:
            on_create(study)
    except optuna.exceptions.DuplicatedStudyError:
        study = None
    if study is None:
        stored = None
        for _ in range(50):   # another worker may be creating it this instant
            study = optuna.load_study(study_name=plan.name, storage=storage, sampler=None, pruner=None)
            stored = stored_plan(study)
            if stored is not None:
                break
            time.sleep(0.2)
        if stored is None:
            raise SnnccError("exists but was not made by snncc hpo (no plan stored)", file=plan.name, field="study")
        diff = stored.differences(plan)
        if diff:
            show = ", ".join(f"{k}: stored {stored.as_dict()[k]!r}, asked {plan.as_dict()[k]!r}" for k in diff[:3])
            raise SnnccError(f"this study was started with other settings ({show}); use another study name",
                             file=plan.name, field="study")
        if plan.n_trials != stored.n_trials:
            merged = stored.as_dict()
            merged["n_trials"] = plan.n_trials
            study.set_user_attr(PLAN_ATTR, merged)
        plan = StudyPlan.from_dict({**stored.as_dict(), "n_trials": plan.n_trials})
        study = optuna.load_study(study_name=plan.name, storage=storage, sampler=_sampler(plan), pruner=_pruner(plan))
    return study, created, plan


def load_study(storage, name: str):
    """An existing study (no sampler needed), or a one-line error."""
    import optuna

    try:
        return optuna.load_study(study_name=name, storage=storage)
    except KeyError:
        known = optuna.get_all_study_names(storage)
        raise SnnccError(f"no such study in this storage (known: {', '.join(known) or 'none'})", file=name,
                         field="study") from None


def best_params(study, objective: str = "accuracy") -> dict:
    """All nine values of the best COMPLETE trial on ``objective`` (ties: the earlier trial)."""
    from optuna.trial import TrialState

    plan = stored_plan(study)
    best = None
    for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
        o = t.user_attrs.get("outcome")
        if not o:
            continue
        v = TrialOutcome(**o).value(objective)
        sign = 1 if directions(plan.target if plan is not None else None)[objective] == "maximize" else -1
        if best is None or sign * v > best[0]:
            best = (sign * v, o["params"])
    if best is None:
        raise SnnccError("has no completed trial to centre a grid on", file=study.study_name, field="study")
    if plan is not None and not set(best[1]) >= set(GRID_KEYS):
        raise SnnccError("its trials lack time_bin_size / nb_input_copies", file=study.study_name, field="study")
    return dict(best[1])


def grid_plan(step1: StudyPlan, step1_best: dict, span: int, name: str | None = None) -> StudyPlan:
    """Step 2's plan: the grid around ``step1_best``; the other seven fixed at their best values."""
    grid = grid_around(step1_best, step1.ranges, span)
    n = len(grid["time_bin_size"]) * len(grid["nb_input_copies"])
    d = step1.as_dict()
    d.update(name=name or f"{step1.name}-grid", step="grid", grid=grid, n_trials=n, restarts=[],
             fixed={k: v for k, v in step1_best.items() if k not in GRID_KEYS}, enqueue_preset=False,
             from_study=step1.name)
    return StudyPlan.from_dict(d)


# --------------------------------------------------------------------------- running

@dataclass
class RunSummary:
    study: str
    step: str
    created: bool
    budget: dict
    trials_run_here: list
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a study; ``trial``: the trial marked FAIL and queued again (or None)."""

    def __init__(self, study: str, trial: int | None):
        super().__init__(study, trial)
        self.study, self.trial = study, trial


def _requeue(study, number: int) -> None:
    """Mark trial ``number`` FAIL (if it is not finished) and queue its parameters again, as for a stale trial."""
    import optuna
    from optuna.trial import TrialState

    trial = next((t for t in study.get_trials(deepcopy=False) if t.number == number), None)
    if trial is None or trial.state in (TrialState.COMPLETE, TrialState.PRUNED):
        return
    if trial.state == TrialState.RUNNING:
        try:
            study._storage.set_trial_state_values(trial._trial_id, state=TrialState.FAIL)
        except optuna.exceptions.UpdateFinishedTrialError:
            pass
    if number in retried_numbers(study.get_trials(deepcopy=False)):
        return
    trial = study._storage.get_trial(trial._trial_id)
    history = list(trial.system_attrs.get("retry_history", [])) + [trial.number]
    system_attrs = {k: v for k, v in trial.system_attrs.items() if k not in ("fixed_params",)}
    system_attrs.update(failed_trial=trial.system_attrs.get("failed_trial", trial.number), retry_history=history)
    system_attrs[INTERRUPTED_ATTR] = True
    # the same record Optuna's RetryHeartbeatStaleTrialCallback queues for a stale trial
    study.add_trial(optuna.create_trial(state=TrialState.WAITING, params=trial.params, distributions=trial.distributions,
                                        user_attrs=trial.user_attrs, system_attrs=system_attrs))


def fail_stale(study) -> None:
    import optuna
    from optuna.exceptions import ExperimentalWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExperimentalWarning)
        optuna.storages.fail_stale_trials(study)


def worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def run_study(plan: StudyPlan, storage, objective_factory: Callable, view=None, poll_s: float = 2.0) -> RunSummary:
    """Run trials of ``plan``'s study until its budget is spent (creating or resuming it).

    ``objective_factory(study, plan)`` returns the objective ``f(trial) -> value(s)`` (it is built after the
    study is opened, so it sees the stored plan). ``view``: progress callbacks (``progress.StudyView``).
    """
    import optuna

    optuna.logging.set_verbosity(optuna.logging.ERROR)   # failures are reported by the view

    def enqueue_preset(study):
        if plan.step == "anneal" and plan.enqueue_preset:
            values = preset_in_space(plan.threshold, plan.ranges)
            if values:
                study.enqueue_trial(values, user_attrs={"paper_preset": plan.threshold})

    study, created, plan = open_study(plan, storage, on_create=enqueue_preset)
    objective = objective_factory(study, plan)
    ran: list[int] = []
    notes: list[str] = []
    if plan.select == "test":
        notes.append("selection on the TEST split, as the paper did: accuracies are optimistic")
    if len(plan.objectives) > 1 and plan.pruner != "none":
        notes.append("several objectives: Optuna's pruners do not apply; every trial runs all its epochs")
    current: dict[str, int | None] = {"trial": None}

    def tracked(trial):
        current["trial"] = trial.number
        if over_budget(study, trial.number, plan.n_trials):
            trial.set_user_attr(OVER_BUDGET_ATTR, True)
            raise SnnccError("cancelled before training: other workers had started the whole budget",
                             field=f"trial {trial.number}")
        return objective(trial)

    catch = (SnnccError,)
    try:
        while True:
            fail_stale(study)
            b = budget(study, plan.n_trials)
            if view is not None:
                view.study_update(b)
            if b.done or (not b.may_start and b.running == 0):
                break
            if not b.may_start:
                if view is not None:
                    view.waiting(b)
                time.sleep(poll_s)
                continue
            current["trial"] = None
            study.optimize(tracked, n_trials=1, catch=catch, gc_after_trial=False)
            if current["trial"] is not None:
                ran.append(current["trial"])
                current["trial"] = None
    except KeyboardInterrupt:
        n = current["trial"]
        if n is not None:
            _requeue(study, n)
        raise Interrupted(plan.name, n) from None
    b = budget(study, plan.n_trials)
    if view is not None:
        view.study_update(b)
    refuse_if_all_failed(study)
    return RunSummary(plan.name, plan.step, created, asdict(b) | {"spent": b.spent}, ran, notes)


def refuse_if_all_failed(study) -> None:
    """Raise the trials' own error if every trial of a finished study failed: the same input
    problem in each (a subset too small to split, say) is bad input, not a result (exit 2)."""
    from collections import Counter

    from optuna.trial import TrialState

    used = counted(study.get_trials(deepcopy=False))
    if not used or any(t.state != TrialState.FAIL for t in used):
        return
    errors = Counter(tuple(t.user_attrs.get("error_parts") or (None, None, t.user_attrs.get("error") or "no error "
                                                                 "recorded")) for t in used)
    (file, field, rule), times = errors.most_common(1)[0]
    how = (f"every one of study {study.study_name}'s {len(used)} trial(s) failed so" if len(errors) == 1 else
           f"{times} of study {study.study_name}'s {len(used)} trials failed so, the others with "
           f"{len(errors) - 1} other error(s); every trial failed")
    raise SnnccError(f"{rule} ({how})", file=file, field=field or "study")
