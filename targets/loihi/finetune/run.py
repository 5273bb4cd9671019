"""Deployment fine-tuning for Loihi 1: the lowered network's integer arithmetic as the student.

    lower      ``lower_model(graph, options)`` as ``compile`` does (scale rule, timing, reset change)
    student    ``DifferentiableLoihi`` over the lowered network (``differentiable.py``): equal to the
               emulator on the registers it exports; the rule's format is kept
    starts     the starting points searched before training (``starts.py``)
    teacher    the graph as trained (its own reset: a subtract-reset graph stays subtract)
    export     a LoihiNetwork with the fine-tuned registers, checked by the compiler's own validation
               (``checks/exactness.validate_lowering``: timing, registers and kernel against the IR)
               against the fine-tuned parameters read back as a float graph (``export.adapted_graph``)

``finetune_loihi`` takes the validated ``LoihiOptions`` record as compile does; what only benches and
studies change (learned registers, surrogate slope, the starting-point search) is ``LoihiStudyKnobs``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit.finetuned import finetune_metadata
from snncc.targets.loihi.options import LoihiOptions, LoihiStudyKnobs


@dataclass
class LoihiFinetuned:
    """The result: the network to write, the lowering it came from, the record, the adapted float graph."""

    network: Any                 # LoihiNetwork with the fine-tuned registers
    lowered: Any                 # LoweredModel (before fine-tuning)
    record: Any                  # kit.finetuning.FinetuneRecord
    adapted: Graph               # the fine-tuned parameters read back in float units (the deployed order)
    validation: dict = field(default_factory=dict)   # validate_lowering of the exported network

    def metadata(self) -> dict:
        """What the bundle records about its fine-tuning (JSON-ready): ``kit.finetuned.finetune_metadata``."""
        return finetune_metadata(self.record)


def loihi_student(lowered, steps: int, **kwargs):
    """The differentiable arithmetic of a LoweredModel (kwargs: learn, slope, detach_reset, device)."""
    from snncc.targets.loihi.finetune.differentiable import DifferentiableLoihi

    names = [c.lif for c in lowered.layers]
    return DifferentiableLoihi(lowered.network, names, lowered.timing_record.shifts, steps, **kwargs)


def network_counts(lowered, steps: int, network, x: np.ndarray) -> np.ndarray:
    """Output spike counts (B, classes) of ``network`` (``lowered``'s layout, any registers) on ``x``, run by the
    bit-exact emulator, over the model's own ``steps`` (population shifts undone)."""
    from snncc.targets.loihi.checks.exactness import lead_steps, loihi_spikes, pad
    from snncc.targets.loihi.emulation.emulator import emulate

    trec = lowered.timing_record
    res = emulate(network, pad(x, lead_steps(trec.shifts, trec.output_shift)), record="all")
    spikes = loihi_spikes(res, network, lowered.layers, trec.shifts, steps)
    return spikes[lowered.layers[-1].lif].sum(axis=1, dtype=np.int64)


def deployed_counts(lowered, steps: int) -> Callable[[Any, np.ndarray], np.ndarray]:
    """``(student, x) -> counts``: the student's exported network through ``network_counts``."""
    return lambda student, x: network_counts(lowered, steps, student.export(), x)


def finetune_loihi(graph: Graph, options: LoihiOptions, split, *, config=None, task_sets: Sequence = (),
                   progress=None, knobs: LoihiStudyKnobs | None = None) -> LoihiFinetuned:
    """Lower ``graph`` with ``options`` (as ``compile``), fine-tune the lowered network towards the
    graph as trained on ``split`` (``kit.finetuning.model_split``), check the result as compile checks a
    lowering. ``config``: ``kit.finetuning.FinetuneConfig``; ``knobs``: what only studies change (default
    ``LoihiStudyKnobs()``: every register learned, slope 5, the starting points searched first)."""
    from snncc.targets.kit.finetuning import FinetuneConfig, finetune, resolve_device
    from snncc.targets.loihi.finetune.export import adapted_graph, validate_export
    from snncc.targets.loihi.finetune.starts import starting_points
    from snncc.targets.loihi.lowering.lower import lower_model

    knobs = knobs or LoihiStudyKnobs()
    config = config or FinetuneConfig()
    steps = int(split.x.shape[1])
    lowered = lower_model(graph, options, t_sample=steps)
    device = resolve_device(config.device)

    def make_student(network):
        from snncc.targets.loihi.finetune.differentiable import DifferentiableLoihi

        return DifferentiableLoihi(network, [c.lif for c in lowered.layers], lowered.timing_record.shifts, steps,
                                   learn=knobs.learn, slope=knobs.slope, device=device)

    student, record = finetune(make_student(lowered.network), lowered.trained, split, config=config,
                               deployed_counts=deployed_counts(lowered, steps),
                               starting_points=starting_points(lowered, make_student) if knobs.search else None,
                               task_sets=list(task_sets), progress=progress)
    network = student.export()
    result = LoihiFinetuned(network=network, lowered=lowered, record=record, adapted=adapted_graph(lowered, network))
    result.validation = validate_export(lowered, network, steps)
    network.metadata["finetune"] = result.metadata()
    if lowered.deployed is not None:
        record.notes.append("the teacher is the graph as trained (its own reset); Loihi runs it with reset to "
                            "zero (--allow-reset-change): the agreement includes the reset change")
    return result
