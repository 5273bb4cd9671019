"""Deployment fine-tuning for Xylo Audio 2: a ``XyloSpec`` trained towards the float graph as trained.

    student   ``DifferentiableXylo`` over the XyloSpec (``differentiable.py``): equal to the bit-exact emulator
              on the registers it exports; decays, shifts and the synapse layout are kept
    teacher   the float graph as trained (its own reset), run by the IR reference simulator
    engine    ``snncc.finetune.engine.finetune``: the same loss, schedule, best-on-validation choice and
              held-out record as every target's fine-tuning (docs/finetune.md)
    measure   the exported spec run by ``emulator.emulate`` (the numba kernel), output event counts

What connects a spec to the graph's populations is the Xylo lowering's: ``hidden`` maps each hidden IR
population to the hidden neurons that carry it (model neurons, in order), ``output`` names the population
Xylo's output neurons carry. The integrator calls ``finetune_xylo`` from the Xylo target's ``finetune``
capability after lowering, and writes ``result.spec`` as it writes any spec.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.xylo.spec import XyloSpec


@dataclass
class XyloFinetuned:
    """The fine-tuned spec and the engine's record (``snncc.finetune.engine.FinetuneRecord``)."""

    spec: XyloSpec
    record: Any

    def metadata(self) -> dict:
        """What the artefact records about its fine-tuning (JSON-ready)."""
        r = self.record
        return {"finetuned": True, "inputs": r.inputs, "seed": r.inputs["seed"], "steps": r.steps,
                "kept_epoch": r.kept_epoch, "agreement_before": r.held_out_before,
                "agreement_after": r.held_out_after, "teacher": "the float graph as trained (its own reset)"}


def deployed_counts(student, x: np.ndarray) -> np.ndarray:
    """Output event counts of the student's exported spec on the bit-exact emulator."""
    from snncc.targets.xylo.emulator import emulate

    return emulate(student.export(), x).counts


def finetune_xylo(spec: XyloSpec, teacher: Graph, split, *, hidden: dict[str, Any], output: str, config=None,
                  task_sets=(), progress=None, learn=("weights", "thresholds", "biases"),
                  slope: float = 5.0) -> XyloFinetuned:
    """Fine-tune ``spec`` towards ``teacher`` on ``split`` (``snncc.finetune.inputs``; inputs in the XyloSpec's
    input channels). ``config``: ``snncc.finetune.engine.FinetuneConfig`` (its step sizes are in register
    units: int8 weights, thresholds, biases); the decays have no step size here (they are kept)."""
    from snncc.finetune.engine import FinetuneConfig, finetune
    from snncc.targets.xylo.differentiable import DifferentiableXylo
    from snncc.training.device import resolve_device

    config = config or FinetuneConfig()
    device = resolve_device(config.device)
    student = DifferentiableXylo(spec, int(split.x.shape[1]), hidden, output, learn=learn, slope=slope, device=device)
    student, record = finetune(student, teacher, split, config=config, deployed_counts=deployed_counts,
                               task_sets=list(task_sets), progress=progress)
    return XyloFinetuned(student.export(), record)
