"""The fine-tuning engine a target trains its lowered model with (imports torch: import it where training runs).

    model_split(graph, inputs, labels, ...)      the inputs split into training, validation and held-out parts
    FinetuneConfig / finetune(student, teacher_graph, split, ...)   the shared loop, loss and keep rule
    TaskSet                                      a task-like set measured before and after
    run_teacher(graph, x, populations)           the float graph's spikes (and pre-reset voltages)
    StudentRun / DifferentiableArithmetic        what a target's differentiable arithmetic returns and offers
    round_ste, trunc_ste, floor_ste, wrap_ste, spike   straight-through integer operations
    resolve_device(spec)                         "auto" | "cpu" | "cuda[:N]" as a torch device, refused in one line
"""

from __future__ import annotations

from snncc.finetune.engine import FinetuneConfig, FinetuneRecord, TaskSet, finetune
from snncc.finetune.inputs import Split, model_split, split_inputs
from snncc.finetune.protocol import DifferentiableArithmetic, StudentRun
from snncc.finetune.ste import floor_ste, round_ste, spike, trunc_ste, wrap_ste
from snncc.finetune.teacher import TeacherRun, run_teacher
from snncc.training.device import resolve_device

__all__ = ["FinetuneConfig", "FinetuneRecord", "TaskSet", "finetune", "Split", "model_split", "split_inputs",
           "DifferentiableArithmetic", "StudentRun", "floor_ste", "round_ste", "spike", "trunc_ste", "wrap_ste",
           "TeacherRun", "run_teacher", "resolve_device"]
