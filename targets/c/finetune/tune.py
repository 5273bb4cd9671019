"""``snncc compile --target c --finetune``: the lowered integer network trained through its own arithmetic
towards the float graph as trained (no labels), with the shared engine (``kit.finetuning.finetune``: loss,
schedule, keep rule, held-out record), then written and checked as every C artefact.

    student   ``student.DifferentiableC`` (weights, thresholds, biases; exponents and decays kept)
    measure   the exported network run by the bit-exact emulator (= the C)
    adapted   the fine-tuned integers read back in float (``checks.stages.stage_graph``: the artefact's weights,
              thresholds and biases, the model's decays): what ``--finetune-out`` writes as NIR
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.c.options import WEIGHT_LIMIT

# Step sizes (Adam moves a shadow about this far per step): weights in int8 units (scaled to int16 units for a
# 16-bit rule), thresholds and biases in units of 2**SHADOW_SHIFT state units (a threshold is about 128..256).
C_LR = {"weights": 0.03, "thresholds": 0.05, "decays": 0.0, "biases": 0.1}
FORWARD_CHECK_SAMPLES = 8


def deployed_counts(student, x: np.ndarray) -> np.ndarray:   # noqa: ANN001
    """Output counts of the student's exported network on the bit-exact emulator."""
    from snncc.targets.c.emulation.emulator import emulate_network

    return emulate_network(student.export(), np.asarray(x)).counts


def forward_equals_emulator(student, x: np.ndarray) -> str:   # noqa: ANN001
    """The student's forward pass against the emulator on the exported integers, every population's spikes."""
    import torch

    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.kit import InternalError

    with torch.no_grad():
        run = student(torch.as_tensor(np.asarray(x), dtype=torch.float64))
    net = student.export()
    em = emulate_network(net, np.asarray(x), record=True)
    for p in net.populations:
        got = run.spikes[p.name].cpu().numpy()
        if not np.array_equal(np.rint(got).astype(np.int64), em.spikes[p.name].astype(np.int64)):
            raise InternalError(f"the fine-tuned network's spikes of {p.name} in the emulator differ from the "
                                "differentiable forward pass it was trained with")
    return (f"the emulator equals the differentiable forward pass on the exported integers (every population's "
            f"spikes) on {x.shape[0]} held-out samples")


def finetune_artefact(graph, inputs, options, finetuning, *, labels=None, data: str | None = None,  # noqa: ANN001
                      progress=None):
    """``target.finetune`` (``options``: ``COptions``; ``finetuning``: ``FinetuneOptions``)."""
    from snncc.targets.c.checks.stages import stage_graph
    from snncc.targets.c.finetune.student import DifferentiableC
    from snncc.targets.c.lowering.lower import lower_network, package_network
    from snncc.targets.kit.finetuned import FinetunedArtefact, finetune_entry
    from snncc.targets.kit.finetuning import FinetuneConfig, finetune, model_split, resolve_device

    device = finetuning.device or "cpu"
    resolve_device(device)
    report = progress or (lambda done, total, phase: None)
    report(0, 1, "lowering and measuring the rules")
    net, selection, steps, steps_rule = lower_network(graph, options)
    split = model_split(graph, inputs, labels, time_steps=options.time_steps, density=finetuning.density,
                        samples=finetuning.finetune_samples, seed=finetuning.finetune_seed, data=data)
    if split.x.shape[1] != net.steps:
        net.steps = int(split.x.shape[1])
    bits = max((q.bits for q in net.projections), default=8)
    lr = {**C_LR, "weights": C_LR["weights"] * WEIGHT_LIMIT[bits] / WEIGHT_LIMIT[8]}
    config = FinetuneConfig(epochs=finetuning.finetune_epochs, seed=finetuning.finetune_seed, device=device, lr=lr)
    student = DifferentiableC(net, int(split.x.shape[1]), device=resolve_device(device))
    student, record = finetune(student, graph, split, config=config, deployed_counts=deployed_counts,
                               progress=progress)
    checked = forward_equals_emulator(student, split.x[split.held_out[:FORWARD_CHECK_SAMPLES]])
    tuned = student.export()
    tuned.steps = steps
    entry = finetune_entry(record)
    artefact = package_network(graph, tuned, options, selection, steps_rule, extra={"finetune": entry},
                               notes=["fine-tuned: weights, thresholds and biases trained through the C target's "
                                      "integer arithmetic towards the float graph as trained; " + checked])
    adapted = None
    refusal = ""
    try:
        adapted = stage_graph(graph, tuned, decays=False)
    except SnnccError as err:        # pragma: no cover - a graph the float reading cannot state
        refusal = str(err)
    return FinetunedArtefact(artefact, record, adapted, refusal)


__all__ = ["finetune_artefact", "C_LR", "deployed_counts", "forward_equals_emulator"]
