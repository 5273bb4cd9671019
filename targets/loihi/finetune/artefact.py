"""The ``finetune`` capability (``snncc compile --finetune``): a fine-tuned bundle, written as any bundle.

``finetune_artefact`` fine-tunes (``run.finetune_loihi``, the engine's default loss and schedule) on the
user's data or seeded random spikes, places the result on cores (``lowering/lower.attach_core_map``) and
checks it as ``lower`` checks a lowering (timing, registers and kernel against the adapted float graph).
It returns the kit's ``FinetunedArtefact``: the ``LoihiArtefact`` of the fine-tuned network (its record
under /snncc/finetune and in /snncc/metadata), the engine's record, and the adapted float graph
(``--finetune-out``).
"""

from __future__ import annotations

from snncc.ir.graph import Graph
from snncc.targets.base import FinetuneOptions
from snncc.targets.kit import InternalError, SnnccError
from snncc.targets.kit.artefact import model_record
from snncc.targets.kit.finetuned import FinetunedArtefact, finetune_entry
from snncc.targets.loihi.options import LoihiOptions

EXACT = ("timing_exact", "quantized_params_exact", "kernel_exact")


def finetune_artefact(graph: Graph, inputs, options: LoihiOptions, finetuning: FinetuneOptions, *, labels=None,
                      data: str | None = None, progress=None) -> FinetunedArtefact:
    """``target.finetune`` (module docstring)."""
    from snncc.targets.kit.finetuning import FinetuneConfig, model_split, resolve_device
    from snncc.targets.loihi.finetune.run import finetune_loihi
    from snncc.targets.loihi.lowering.artefact import LoihiArtefact
    from snncc.targets.loihi.lowering.lower import attach_core_map
    from snncc.targets.loihi.mapping.relays import needs_relays

    device = finetuning.device or "cpu"
    resolve_device(device)                      # an unavailable device is refused before any work
    split = model_split(graph, inputs, labels, time_steps=options.time_steps, density=finetuning.density,
                        samples=finetuning.finetune_samples, seed=finetuning.finetune_seed, data=data)
    config = FinetuneConfig(epochs=finetuning.finetune_epochs, seed=finetuning.finetune_seed, device=device)
    result = finetune_loihi(graph, options, split, config=config, progress=progress)
    network = result.network
    if needs_relays(network):
        raise SnnccError("fine-tuning a network whose fan-in needs relay neurons is not supported", field="--finetune")
    attach_core_map(network)
    checks = result.validation
    if not all(checks.get(k) for k in EXACT):
        raise InternalError("the fine-tuned bundle differs from its adapted float graph in the emulator "
                            f"({ {k: checks.get(k) for k in EXACT} })")
    lowered = result.lowered
    notes = list(lowered.notes) + [f"tSample {network.t_sample}: {network.metadata['t_sample_rule']}"]
    notes.append("fine-tuned: registers trained through Loihi's integer arithmetic towards the float graph as "
                 "trained; the checks above compare the bundle with the adapted float graph (--finetune-out)")
    bundle = LoihiArtefact(network=network, quantization=lowered.quant_record.as_dict(),
                           timing=lowered.timing_record.as_dict(), validation=checks, notes=notes,
                           finetune=finetune_entry(result.record), model=model_record(graph))
    return FinetunedArtefact(bundle, result.record, adapted=result.adapted)
