"""The fine-tuning loop: distil the float graph (teacher) into a target's integer arithmetic (student).

    teacher   the float graph as trained, its own reset, run once on all inputs by the IR reference
              simulator (``teacher.py``): output counts, every population's spikes (and V / theta)
    student   the target's ``DifferentiableArithmetic`` built from the lowered, quantized model
    loss      ``loss.distillation_loss`` (no labels)
    start     a target may first measure starting points on the validation part (equivalent or nearby
              register choices: ``starting_points``) and start from the best
    schedule  Adam, one step size per parameter kind, cosine decay to 0 over all steps; the first
              ``force_epochs`` epochs teacher-force the hidden populations (every synapse leaving
              them reads the teacher's spikes, so each layer learns its own map), the rest run free
    keep      after every epoch the deployed integers are measured on the validation part (argmax
              agreement with the teacher, clear-winner rule); an epoch replaces the kept parameters when
              it is better on validation than they are AND better than the starting point (epoch 0) by a
              paired one-sided sign test on the validation samples at p < KEEP_P: a gain of a few samples
              is noise, and keeping it cost held-out agreement (measured: +3 of 459 validation samples
              kept, -18 of 911 held-out). So the result is never worse on validation, and leaves the
              start only on evidence
    report    agreement before and after on the held-out part only (never trained on, never used
              for a choice), with its 95 % Wilson interval; the same on task-like sets, and task
              accuracy where they have labels

Deterministic for a seed on one device (torch and numpy seeded; shuffles seeded per epoch).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any, Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.measure.agreement import (ArgmaxAgreement, accuracy, argmax_agreement, argmax_hits, count_correlation,
                                     sign_test)
from snncc.finetune.inputs import Split
from snncc.finetune.loss import LossWeights, distillation_loss

Progress = Callable[[int, int, str], None]
DEFAULT_LR = {"weights": 0.03, "thresholds": 0.05, "decays": 0.3, "biases": 0.1}   # measured: docs/finetune.md
SELF_CHECK_SAMPLES = 8
KEEP_P = 0.05       # a trained epoch is kept only if it beats the start on validation at this one-sided p


@dataclass(frozen=True)
class FinetuneConfig:
    """The schedule. Step sizes are in register units (half weight mantissas, threshold mantissas,
    decay registers, bias mantissas): Adam moves each shadow by about ``lr`` per step."""

    epochs: int = 6
    force_epochs: int = 0
    batch: int = 64
    lr: dict = field(default_factory=lambda: dict(DEFAULT_LR))
    cosine: bool = True
    loss: LossWeights = field(default_factory=LossWeights)
    seed: int = 0
    device: str = "cpu"
    max_cpu_s: float | None = None      # stop training (and keep the best so far) past this CPU time

    def __post_init__(self) -> None:
        for name in ("epochs", "batch"):
            v = getattr(self, name)
            if not (isinstance(v, int) and v >= 1):
                raise SnnccError(f"must be a whole number >= 1, got {v}", field=name)
        if not (isinstance(self.force_epochs, int) and 0 <= self.force_epochs <= self.epochs):
            raise SnnccError(f"must be a whole number in 0..epochs ({self.epochs}), got {self.force_epochs}",
                             field="force_epochs")
        for k, v in self.lr.items():
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise SnnccError(f"step sizes must be finite numbers >= 0, got {v}", field=f"lr.{k}")
        if self.max_cpu_s is not None and not self.max_cpu_s > 0:
            raise SnnccError(f"must be > 0, got {self.max_cpu_s}", field="max_cpu_s")

    def as_dict(self) -> dict:
        d = asdict(self)
        d["loss"] = self.loss.as_dict()
        return d


@dataclass
class TaskSet:
    """Extra inputs the result is reported on (never trained on): e.g. task-like Braille events."""

    name: str
    x: np.ndarray
    labels: np.ndarray | None = None
    description: str = ""


@dataclass
class FinetuneRecord:
    """What fine-tuning did and what it achieved (``as_dict`` is JSON-ready)."""

    inputs: dict
    config: dict
    device: str
    epochs_run: int
    steps: int                            # optimiser steps taken
    kept_epoch: int                       # 0: no epoch beat the starting point on validation (paired, KEEP_P)
    starting_points: list[dict]           # candidates measured on validation before training (the first chosen
                                          # unless another is better)
    validation: list[dict]                # per epoch: agreement on the validation part
    held_out_before: dict
    held_out_after: dict
    count_correlation_before: float | None     # None: undefined (constant counts)
    count_correlation_after: float | None
    task: dict[str, dict] = field(default_factory=dict)
    wall_s: float = 0.0
    cpu_s: float = 0.0
    stopped: str = ""                     # why training stopped early ("" when all epochs ran)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)

    def lines(self) -> list[str]:
        b, a = self.held_out_before, self.held_out_after
        out = [f"fine-tuned on {self.inputs['description']}: {self.inputs['train']} training, "
               f"{self.inputs['validation']} validation, {self.inputs['held_out']} held-out samples (seed "
               f"{self.inputs['seed']}), {self.steps} optimiser steps on {self.device}, kept epoch {self.kept_epoch} of "
               f"{self.epochs_run}, {self.cpu_s:.0f} s CPU / {self.wall_s:.0f} s wall",
               f"  held-out argmax agreement with the float graph: {_text(b)} -> {_text(a)}",
               f"  held-out count correlation: {_corr(self.count_correlation_before)} -> "
               f"{_corr(self.count_correlation_after)}"]
        if len(self.validation) > 1:
            out.append("  validation by epoch: " + ", ".join(_epoch_text(v) for v in self.validation)
                       + f" (a trained epoch is kept only if it beats epoch 0 at one-sided p < {KEEP_P:g})")
        if self.starting_points:
            out.append("  starting point: " + ", ".join(f"{c['name']} {c['validation']:.3f}"
                                                         for c in self.starting_points) + " (validation agreement)")
        for name, t in self.task.items():
            out.append(f"  {name}: agreement {_text(t['before'])} -> {_text(t['after'])}")
            if "accuracy" in t:
                acc = t["accuracy"]
                out.append(f"    task accuracy: float {_pct(acc['float'])}, deployed {_pct(acc['before'])} -> "
                           f"{_pct(acc['after'])}; deployed - float {100 * acc['difference']:+.2f} points "
                           f"[{100 * acc['difference_low']:+.2f}, {100 * acc['difference_high']:+.2f}]")
        if self.stopped:
            out.append(f"  stopped early: {self.stopped}")
        out += [f"  note: {n}" for n in self.notes]
        return out


def _text(d: dict) -> str:
    return ArgmaxAgreement(**d).text()


def _corr(v: float | None) -> str:
    return "undefined (constant counts)" if v is None else f"{v:.4f}"


def _pct(d: dict) -> str:
    if d["value"] is None:
        return "undefined (no samples)"
    return f"{100 * d['value']:.2f} % [{100 * d['low']:.2f}, {100 * d['high']:.2f}]"


def paired_difference(pred_a: np.ndarray, pred_b: np.ndarray, labels: np.ndarray) -> tuple[float, float, float]:
    """acc(a) - acc(b) on the same samples, with a 95 % interval for paired proportions (Wald, from the
    discordant pairs: se = sqrt(n10 + n01 - (n10 - n01)**2 / n) / n)."""
    ra, rb = pred_a == labels, pred_b == labels
    n = labels.size
    n10, n01 = int(np.count_nonzero(ra & ~rb)), int(np.count_nonzero(~ra & rb))
    d = (n10 - n01) / n
    se = math.sqrt(max(n10 + n01 - (n10 - n01) ** 2 / n, 0.0)) / n
    return d, d - 1.959963984540054 * se, d + 1.959963984540054 * se


def _student_counts(student, x: np.ndarray, batch: int) -> np.ndarray:
    import torch

    out = []
    with torch.no_grad():
        for s in range(0, x.shape[0], batch):
            out.append(student(torch.as_tensor(x[s:s + batch])).counts.cpu().numpy())
    return np.rint(np.concatenate(out)).astype(np.int64)


StartingPoints = Callable[[Any, Callable[[Any], float], tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]],
                          tuple[Any, list[dict]]]


def finetune(student, teacher_graph, split: Split, *, config: FinetuneConfig | None = None,
             deployed_counts: Callable[[Any, np.ndarray], np.ndarray] | None = None,
             starting_points: StartingPoints | None = None,
             task_sets: list[TaskSet] = (), progress: Progress | None = None):
    """Fine-tune ``student`` (a ``DifferentiableArithmetic``) towards ``teacher_graph`` on ``split``.

    ``deployed_counts(student, x)``: output counts of the student's exported integers on the target's
    own emulator (default: the student's forward pass, which equals it). ``starting_points(student,
    score, train)``: a target's search among equivalent or nearby starting points, ``score(candidate)``
    being the candidate's validation agreement, ``train`` = (all inputs, the teacher's spikes per population
    on them, the training part's indices); returns (the chosen student, [{"name", "validation"}, ...]).
    Returns (student with the kept parameters loaded, ``FinetuneRecord``)."""
    import torch

    from snncc.finetune.teacher import run_teacher
    from snncc.threads import one_thread
    from snncc.training.device import resolve_device

    config = config or FinetuneConfig()
    device = resolve_device(config.device)
    wall0, cpu0 = time.time(), time.process_time()
    populations = tuple(student.populations)
    hidden = populations[:-1]
    if split.x.shape[1] != student.steps:
        raise SnnccError(f"inputs have {split.x.shape[1]} steps, the model runs {student.steps}", field="inputs")
    measure = deployed_counts or (lambda st, x: _student_counts(st, x, 256))
    report = progress or (lambda done, total, phase: None)

    with one_thread():
        torch.manual_seed(config.seed)
        want_v = config.loss.voltage > 0
        report(0, split.x.shape[0], "teacher")
        teacher = run_teacher(teacher_graph, split.x, populations, voltage=want_v,
                              progress=lambda d: report(d, split.x.shape[0], "teacher"))
        tasks = {t.name: run_teacher(teacher_graph, t.x, populations, voltage=False) for t in task_sets}

        def agreement_on(idx: np.ndarray, who=None) -> ArgmaxAgreement:
            return argmax_agreement(teacher.counts[idx], measure(student if who is None else who, split.x[idx]))

        def validation_run() -> tuple[ArgmaxAgreement, np.ndarray]:
            """The student's validation agreement and its per-sample hits (clear-winner samples)."""
            got = measure(student, split.x[split.validation])
            ref = teacher.counts[split.validation]
            return argmax_agreement(ref, got), argmax_hits(ref, got)

        held_before_counts = measure(student, split.x[split.held_out])
        held_before = argmax_agreement(teacher.counts[split.held_out], held_before_counts)
        task_before = {t.name: measure(student, t.x) for t in task_sets}
        trace: list[dict] = []
        if starting_points is not None:
            report(0, 1, "starting points")
            train = (split.x, teacher.spikes, split.train)
            student, trace = starting_points(student, lambda cand: _score(agreement_on(split.validation, cand)), train)
            report(1, 1, "starting points")
        groups = student.param_groups()
        unknown = set(groups) - set(config.lr)
        if unknown:
            raise SnnccError(f"no step size for parameter kinds {sorted(unknown)}", field="lr")
        params = [{"params": ps, "lr": config.lr[k]} for k, ps in groups.items() if ps and config.lr[k] > 0]
        if not params:
            raise SnnccError("nothing to train: every parameter kind has step size 0 or no parameters", field="lr")
        opt = torch.optim.Adam(params)
        per_epoch = -(-split.train.size // config.batch)
        total = config.epochs * per_epoch
        sched = torch.optim.lr_scheduler.LambdaLR(
            opt, lambda i: 0.5 * (1.0 + math.cos(math.pi * min(i, total) / total)) if config.cosine else 1.0)
        val0, hits0 = validation_run()
        history = [{"epoch": 0, **val0.as_dict()}]
        best_value, best_epoch = _score(val0), 0
        best_state = {k: v.detach().clone() for k, v in student.state_dict().items()}
        steps, stopped, epoch = 0, "", 0
        as_t = dict(dtype=torch.float64, device=device)
        for epoch in range(1, config.epochs + 1):
            order = np.random.default_rng((config.seed, epoch)).permutation(split.train)
            forced = epoch <= config.force_epochs and bool(hidden)
            for b in range(0, order.size, config.batch):
                idx = order[b:b + config.batch]
                t_b = {"counts": torch.as_tensor(teacher.counts[idx], **as_t),
                       "spikes": {p: torch.as_tensor(teacher.spikes[p][idx], **as_t) for p in hidden},
                       "voltage": {p: torch.as_tensor(teacher.voltage[p][idx], **as_t) for p in hidden} if want_v
                       else {}}
                run = student(torch.as_tensor(split.x[idx], **as_t), force=t_b["spikes"] if forced else None)
                loss = distillation_loss(run, t_b, config.loss, hidden)
                opt.zero_grad()
                loss.backward()
                opt.step()
                sched.step()
                student.project()
                steps += 1
                report(steps, total, "training")
            val, hits = validation_run()
            better, worse = int(np.count_nonzero(hits & ~hits0)), int(np.count_nonzero(~hits & hits0))
            p_start = sign_test(better, worse)
            history.append({"epoch": epoch, **val.as_dict(),
                            "vs_start": {"better": better, "worse": worse, "p": p_start}})
            if _score(val) > best_value and p_start < KEEP_P:
                best_value, best_epoch = _score(val), epoch
                best_state = {k: v.detach().clone() for k, v in student.state_dict().items()}
            if config.max_cpu_s is not None and time.process_time() - cpu0 > config.max_cpu_s and epoch < config.epochs:
                stopped = f"CPU time {time.process_time() - cpu0:.0f} s exceeded max_cpu_s {config.max_cpu_s:g}"
                break
        student.load_state_dict(best_state)
        report(0, 1, "evaluating")
        held_after_counts = measure(student, split.x[split.held_out])
        _self_check(student, split.x[split.held_out[:SELF_CHECK_SAMPLES]], held_after_counts[:SELF_CHECK_SAMPLES])
        task_out: dict[str, dict] = {}
        for t in task_sets:
            after = measure(student, t.x)
            entry = {"description": t.description, "samples": int(t.x.shape[0]),
                     "before": argmax_agreement(tasks[t.name].counts, task_before[t.name]).as_dict(),
                     "after": argmax_agreement(tasks[t.name].counts, after).as_dict()}
            if t.labels is not None:
                f_pred = np.argmax(tasks[t.name].counts, axis=1)
                a_pred = np.argmax(after, axis=1)
                d, lo, hi = paired_difference(a_pred, f_pred, t.labels)
                entry["accuracy"] = {"float": accuracy(f_pred, t.labels),
                                     "before": accuracy(np.argmax(task_before[t.name], axis=1), t.labels),
                                     "after": accuracy(a_pred, t.labels), "difference": d, "difference_low": lo,
                                     "difference_high": hi}
            task_out[t.name] = entry
        report(1, 1, "evaluating")
    held_t = teacher.counts[split.held_out]
    record = FinetuneRecord(
        inputs=split.as_dict(), config=config.as_dict(), device=str(device), epochs_run=epoch, steps=steps,
        kept_epoch=best_epoch, starting_points=trace, validation=history, held_out_before=held_before.as_dict(),
        held_out_after=argmax_agreement(held_t, held_after_counts).as_dict(),
        count_correlation_before=count_correlation(held_before_counts, held_t),
        count_correlation_after=count_correlation(held_after_counts, held_t), task=task_out,
        wall_s=time.time() - wall0, cpu_s=time.process_time() - cpu0, stopped=stopped)
    if split.source == "synthetic":
        record.notes.append("random spike trains: agreement with the float graph, not accuracy on real data")
    return student, record


def _epoch_text(v: dict) -> str:
    """One epoch's validation figure, with its paired comparison with the start where there is one."""
    text = "undefined" if v["share"] is None else f"{v['share']:.3f}"
    if "vs_start" in v:
        c = v["vs_start"]
        text += f" (+{c['better']}/-{c['worse']}, p {c['p']:.2g})"
    return text


def _score(a: ArgmaxAgreement) -> float:
    return -1.0 if a.share is None else a.share


def _self_check(student, x: np.ndarray, deployed: np.ndarray) -> None:
    """The student's forward pass must give the deployed integers' counts (what was optimised is what runs)."""
    mine = _student_counts(student, x, max(1, x.shape[0]))
    if not np.array_equal(mine, deployed):
        raise SnnccError("internal check failed: the fine-tuned student's forward pass differs from the target's "
                         "emulator on the exported integers", field="finetune")
