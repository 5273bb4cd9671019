"""``snncc hpo run`` as a Python function: the two steps, on one storage, resumable.

``step="both"`` runs step 1 (annealing, study NAME) and then step 2 (grid, study NAME-grid,
centred on step 1's best accuracy); rerunning continues whichever is unfinished.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from snncc.targets import DEFAULT_TARGET
from snncc.errors import SnnccError
from snncc.hpo.annealing import evenly_spaced_restarts
from snncc.hpo.trial import TrialObjective
from snncc.hpo.space import search_space, space_as_dict
from snncc.hpo.storage import check_url, check_writable, default_url, open_storage, storage_errors
from snncc.hpo.study import StudyPlan, best_params, grid_plan, load_study, run_study, worker_name

if TYPE_CHECKING:
    from snncc.hpo.progress import StudyView


@dataclass
class HpoRequest:
    name: str
    data: str
    threshold: int = 1
    step: str = "both"                # "anneal" | "grid" | "both"
    trials: int = 600                 # step 1's budget (the paper: 600)
    restarts: int = 2                 # evenly spaced re-initialisations (the paper: 2)
    grid_span: int = 1
    objectives: tuple = ("accuracy",)
    ranges: list = field(default_factory=list)     # ["tau_mem=0.02:0.1", ...]
    kind: str = "rsnn"
    epochs: int = 300
    subset: int | None = None
    seed: int = 0
    val_fraction: float = 0.2
    select: str = "val"
    batch_size: int = 128
    n_hidden: int | None = None
    energy_samples: int = 16
    emulate_samples: int = 0
    pruner: str = "median"
    n_startup: int = 3
    enqueue_preset: bool = True
    storage: str | None = None        # default: sqlite in workdir
    workdir: str = "hpo"
    device: str = "auto"
    heartbeat: int = 30
    target: str = DEFAULT_TARGET             # whose hardware figures cost each trial
    target_options: dict = field(default_factory=dict)   # its lower options (compile's flags), given values only


def _anneal_plan(req: HpoRequest, source) -> StudyPlan:
    ranges = list(req.ranges)
    if source is not None and source.fixed_bin_ms is not None:   # an encoded .npz: its bin is the only time_bin_size
        if any(r.split("=", 1)[0].strip() == "time_bin_size" for r in ranges):
            raise SnnccError(f"this .npz is binned at {source.fixed_bin_ms:g} ms; time_bin_size cannot be searched "
                             "(give a directory of published Braille files)", file=source.path, field="--range")
        ranges.append(f"time_bin_size={source.fixed_bin_ms:g}")
    space = search_space(ranges)
    return StudyPlan(name=req.name, step="anneal", data=str(Path(req.data).resolve()), threshold=req.threshold,
                     objectives=tuple(req.objectives), n_trials=req.trials, space=space_as_dict(space),
                     restarts=evenly_spaced_restarts(req.trials, req.restarts), kind=req.kind, epochs=req.epochs,
                     subset=req.subset, seed=req.seed, val_fraction=req.val_fraction, select=req.select,
                     batch_size=req.batch_size, n_hidden=req.n_hidden, energy_samples=req.energy_samples,
                     emulate_samples=req.emulate_samples, pruner=req.pruner, n_startup=req.n_startup,
                     enqueue_preset=req.enqueue_preset, target=req.target,
                     target_options=dict(req.target_options))


def check_request(req: HpoRequest) -> None:
    if req.step not in ("anneal", "grid", "both"):
        raise SnnccError("must be anneal, grid or both", field="--step")
    if req.restarts < 0:
        raise SnnccError("must be >= 0", field="--restarts")
    if req.n_startup < 1:
        raise SnnccError("must be >= 1", field="--startup")
    if req.grid_span < 0:
        raise SnnccError("must be >= 0", field="--grid-span")
    if req.threshold not in (1, 2, 5, 10):
        raise SnnccError("must be 1, 2, 5 or 10 (the paper's presets)", field="--threshold")
    if req.heartbeat < 1:
        raise SnnccError("must be >= 1 (seconds)", field="--heartbeat")


def check_sizes(plan: StudyPlan, source) -> None:
    """Refuse, before any trial, a model too large for this machine at the plan's largest input copies
    and finest time bin (``snncc.models.size``)."""
    from snncc.data.binning import n_bins_for
    from snncc.models import SNNConfig
    from snncc.models.size import check_snn_size
    from snncc.training.pipeline import N_SNN_OUTPUTS

    ranges = plan.ranges
    if source.fixed is not None:
        steps = int(source.fixed.inputs.shape[1])
    else:
        steps = n_bins_for(source.record_ms, ranges["time_bin_size"].low)
    check_snn_size(source.channels, int(ranges["nb_input_copies"].high), plan.n_hidden or SNNConfig.n_hidden,
                   N_SNN_OUTPUTS, plan.kind == "rsnn", min(plan.batch_size, int(source.labels.shape[0])), steps)


def check_split(plan: StudyPlan, source) -> None:
    """Every trial splits the same samples the same way (``--subset``, ``--seed``, ``--val-fraction``):
    a split that cannot be made is refused before any trial, not found in each."""
    from snncc.data.split import stratified_split
    from snncc.training.training_set import subset_indices

    labels = np.asarray(source.labels)
    try:
        chosen = subset_indices(labels, plan.subset, plan.seed)
        stratified_split(labels[chosen], seed=plan.seed, val_fraction=plan.val_fraction if plan.select == "val" else 0.0)
    except SnnccError as err:
        raise err.with_file(source.path) from None


def run_hpo(req: HpoRequest, view: StudyView | None = None) -> list:
    """Run (or resume) the requested step(s); returns one ``RunSummary`` per step run.

    ``view``: the progress callbacks (``snncc.hpo.progress.StudyView``), told ``study_start(name)``
    before each step and ``close()`` after it; None: silent."""
    from snncc.hpo.search_events import load_source

    check_request(req)
    _anneal_plan(req, None).check()   # bad settings and ranges fail before anything is opened or loaded
    url = req.storage or default_url(req.workdir)
    where = "--storage" if req.storage else "--dir"
    check_writable(url, where)
    if req.storage is not None:
        check_url(url, req.heartbeat)
    source = load_source(req.data, req.threshold)
    step1 = _anneal_plan(req, source)
    step1.check()
    check_sizes(step1, source)
    check_split(step1, source)
    # only now, with everything checked, is anything created: the --dir and its SQLite file
    if req.storage is None:
        Path(req.workdir).mkdir(parents=True, exist_ok=True)
    storage = open_storage(url, req.heartbeat)
    worker = worker_name()
    summaries = []

    def factory(study, plan):
        return TrialObjective(plan, source, req.workdir, req.device, view=view, worker=worker)

    def run(plan):
        if view is not None:
            view.study_start(plan.name)
        try:
            with storage_errors(url, where):
                return run_study(plan, storage, factory, view=view)
        finally:
            if view is not None:
                view.close()

    if req.step in ("anneal", "both"):
        summaries.append(run(step1))
    if req.step in ("grid", "both"):
        study1 = load_study(storage, req.name)
        from snncc.hpo.study import stored_plan

        stored = stored_plan(study1)
        if stored is None or stored.step != "anneal":
            raise SnnccError("is not a step-1 (annealing) study of snncc hpo", file=req.name, field="study")
        if stored.data != step1.data or stored.threshold != step1.threshold:
            raise SnnccError(f"step 1 ran on {stored.data} (threshold {stored.threshold}); give the same data",
                             file=req.name, field="--data")
        plan2 = grid_plan(stored, best_params(study1, "accuracy"), req.grid_span)
        summaries.append(run(plan2))
    return summaries
