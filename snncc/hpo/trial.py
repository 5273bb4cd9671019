"""One trial: train with the existing trainer, report each epoch to the pruner, compile for Loihi.

The trial's nine values come from the sampler (``space.suggest``); the model is trained by
``snncc.training.pipeline.train`` on the data binned at its time_bin_size, its checkpoint kept
in the work directory (``trial_<number>.pt``), and ``hardware.hardware_figures`` compiles it.
The value(s) returned are the plan's objectives, in order (``outcome.TrialOutcome.value``).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from snncc.errors import SnnccError
from snncc.hpo.outcome import TrialOutcome
from snncc.hpo.space import as_params, suggest


class TrialObjective:
    """``f(trial)`` for ``study.optimize``: see the module doc."""

    def __init__(self, plan, source, workdir: str | Path, device: str = "auto", view=None, worker: str = ""):
        self.plan = plan
        self.source = source
        self.workdir = Path(workdir)
        self.device = device
        self.view = view
        self.worker = worker

    def checkpoint_path(self, number: int) -> Path:
        return self.workdir / self.plan.name / f"trial_{number:05d}.pt"

    def __call__(self, trial):
        try:
            return self._run(trial)
        except SnnccError as err:
            trial.set_user_attr("error", err.line())
            trial.set_user_attr("error_parts", [err.file, err.field, err.rule])
            if self.view is not None:
                self.view.trial_error(trial.number, err.line())
            raise

    def _run(self, trial):
        import optuna

        from snncc.frontends.torchfile import load_torch_file
        from snncc.hpo.hardware import hardware_figures
        from snncc.training.pipeline import TrainRequest, assigned, train

        plan = self.plan
        values = suggest(trial, plan.ranges, plan.fixed)
        hp = as_params(values)
        trial.set_user_attr("worker", self.worker)
        ckpt = self.checkpoint_path(trial.number)
        ckpt.parent.mkdir(parents=True, exist_ok=True)
        if self.view is not None:
            self.view.trial_start(trial.number, plan.epochs, hp.as_dict())
        data = self.source.binned(hp.time_bin_size)
        single = len(plan.objectives) == 1
        curve: list[float] = []

        def on_epoch(record):
            metric = record.val_accuracy if plan.select == "val" else record.test_accuracy
            curve.append(float(metric))
            if self.view is not None:
                self.view.trial_epoch(record, metric)
            if single:
                trial.report(float(metric), record.epoch)
                if trial.should_prune():
                    trial.set_user_attr("epoch_metric", curve)
                    raise optuna.TrialPruned(f"epoch {record.epoch}: {plan.select} accuracy {metric:.4f}")

        req = TrainRequest(kind=plan.kind, data=self.source.path, output=str(ckpt), threshold=plan.threshold,
                           epochs=plan.epochs, subset=plan.subset, seed=plan.seed, order=plan.order,
                           val_fraction=plan.val_fraction if plan.select == "val" else 0.0,
                           batch_size=plan.batch_size, overrides=hp.as_dict(), device=self.device,
                           n_hidden=plan.n_hidden)
        started = time.perf_counter()
        result = train(req, data=data, on_epoch=on_epoch)
        train_seconds = time.perf_counter() - started
        trial.set_user_attr("epoch_metric", curve)
        h = result.history
        # held-out samples of this trial's own split: the selection split (validation, or test)
        meta = load_torch_file(str(ckpt)).get("metadata", {})
        held = assigned(meta["split_assignment"], plan.select)
        # a seeded shuffle: the estimate and the emulation see a mix of classes, not the first few (sorted) ones
        held = held[np.random.default_rng(plan.seed).permutation(held.size)]
        inputs = data.inputs[held].numpy()
        labels = data.labels[held].numpy()
        if self.view is not None:
            self.view.trial_phase(f"compiling for {plan.target}, measuring its hardware figures"
                                  + (", emulating" if plan.emulate_samples else ""))
        hw = hardware_figures(ckpt, inputs, labels, plan.energy_samples, plan.emulate_samples, target=plan.target,
                              options=plan.target_options)
        accuracy = h["val_accuracy"] if plan.select == "val" else h["test_accuracy"]
        outcome = TrialOutcome(
            params=hp.as_dict(), accuracy=float(accuracy), selected_on=plan.select,
            val_accuracy=h["val_accuracy"], test_accuracy=float(h["test_accuracy"]), best_epoch=int(h["best_epoch"]),
            epochs_run=int(h["epochs_run"]), hardware=hw.as_dict(), checkpoint=str(ckpt),
            synthetic_data=bool(self.source.synthetic), worker=self.worker, train_seconds=train_seconds,
            notes=(["SYNTHETIC data"] if self.source.synthetic else [])
            + (["selected on TEST (optimistic)"] if plan.select == "test" else []), target=plan.target)
        trial.set_user_attr("outcome", outcome.as_dict())
        values_out = [outcome.value(o) for o in plan.objectives]
        if self.view is not None:
            self.view.trial_done(trial.number, outcome)
        if not np.all(np.isfinite(values_out)):
            raise SnnccError(f"objective values not finite: {values_out}", field=f"trial {trial.number}")
        return values_out[0] if single else tuple(values_out)
