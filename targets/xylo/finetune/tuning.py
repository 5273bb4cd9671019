"""Deployment fine-tuning for Xylo Audio 2: a ``XyloSpec`` trained towards the float graph as trained.

    student   ``DifferentiableXylo`` over the XyloSpec (``arithmetic.py``): equal to the bit-exact emulator
              on the registers it exports; decays, shifts and the synapse layout are kept
    teacher   the float graph as trained (its own reset), run by the IR reference simulator
    engine    ``kit.finetuning.finetune``: the same loss, schedule, best-on-validation choice and
              held-out record as every target's fine-tuning (docs/finetune.md)
    measure   the exported spec run by ``emulation.emulator.emulate`` (the numba kernel), output event counts

What connects a spec to the graph's populations is the Xylo lowering's: ``hidden`` maps each hidden IR
population to the hidden neurons that carry it (model neurons, in order), ``output`` names the population
Xylo's output neurons carry.

The target's ``finetune`` capability (``snncc compile --target xylo --finetune``) is ``finetune_artefact``:
lower as ``compile`` does, fine-tune the lowered spec in the model's own time (``student.py``: the
lowering's feed and population shifts, its synapse layout and bias source kept), check that the emulator
equals the differentiable forward pass on the exported integers, then write it as every Xylo artefact
(``artefact/write.py``: spec.npz read back and run beside the in-memory spec) with a ``finetune`` entry in
manifest.json (``kit.finetuned``). ``--finetune-out`` is refused: a Xylo spec has no faithful float NIR reading (below).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit import InternalError, SnnccError
from snncc.targets.kit.finetuned import FinetunedArtefact, finetune_entry, finetune_metadata
from snncc.targets.xylo.options import XyloOptions
from snncc.targets.xylo.spec import XyloSpec

# Step sizes in register units (int8 weights, threshold and bias units): Adam moves a shadow about this far per
# step. Measured on the subtract Braille graph's auto lowering (docs/finetune.md): 0.3 / 10 / 3 and 0.1 / 3 / 1 drop
# validation agreement by 5-16 points in the first epoch; these keep it within 5 points of the start.
XYLO_LR = {"weights": 0.03, "thresholds": 1.0, "decays": 0.0, "biases": 0.3}
FORWARD_CHECK_SAMPLES = 8
FINETUNE_OUT_REFUSAL = ("a fine-tuned Xylo spec has no faithful float NIR reading (shift decays, int16 saturation, "
                        "multi-spike events, feed timing): its network is spec.npz")


@dataclass
class XyloFinetuned:
    """The fine-tuned spec and the engine's record (``snncc.finetune.engine.FinetuneRecord``)."""

    spec: XyloSpec
    record: Any

    def metadata(self) -> dict:
        """What the artefact records about its fine-tuning (JSON-ready; ``kit.finetuned.finetune_metadata``)."""
        return finetune_metadata(self.record)


def deployed_counts(student, x: np.ndarray) -> np.ndarray:
    """Output event counts of the student's exported spec on the bit-exact emulator."""
    from snncc.targets.xylo.emulation.emulator import emulate

    return emulate(student.export(), x).counts


def finetune_xylo(spec: XyloSpec, teacher: Graph, split, *, hidden: dict[str, Any], output: str, config=None,
                  task_sets=(), progress=None, learn=("weights", "thresholds", "biases"),
                  slope: float = 5.0) -> XyloFinetuned:
    """Fine-tune ``spec`` towards ``teacher`` on ``split`` (``kit.finetuning.model_split``; inputs in the XyloSpec's
    input channels). ``config``: ``kit.finetuning.FinetuneConfig`` (its step sizes are in register
    units: int8 weights, thresholds, biases); the decays have no step size here (they are kept)."""
    from snncc.targets.kit.finetuning import FinetuneConfig, finetune, resolve_device
    from snncc.targets.xylo.finetune.arithmetic import DifferentiableXylo

    config = config or FinetuneConfig()
    device = resolve_device(config.device)
    student = DifferentiableXylo(spec, int(split.x.shape[1]), hidden, output, learn=learn, slope=slope, device=device)
    student, record = finetune(student, teacher, split, config=config, deployed_counts=deployed_counts,
                               task_sets=list(task_sets), progress=progress)
    return XyloFinetuned(student.export(), record)


# -- the lowered model: compile --finetune ------------------------------------------------------------------
@dataclass
class XyloLoweredFinetuned:
    """The lowering with the fine-tuned spec, the student it came from, and the engine's record."""

    lowered: Any                 # lowering.lower.XyloLowered with the fine-tuned spec (its twin rebuilt)
    before: Any                  # lowering.lower.XyloLowered as lowered
    student: Any                 # student.ChipTimeStudent with the kept parameters
    record: Any                  # kit.finetuning.FinetuneRecord
    forward_check: str = ""      # the emulator against the differentiable forward pass, on the exported integers

    def metadata(self) -> dict:
        return XyloFinetuned(self.lowered.xylo_spec, self.record).metadata()


def lowered_student(low, steps: int, *, learn=("weights", "thresholds", "biases"), slope: float = 5.0, device=None):
    """The differentiable arithmetic of a ``lowering.lower.XyloLowered`` in the model's time (``student.py``)."""
    from snncc.targets.xylo.finetune.student import ChipTimeStudent

    hidden = {r.name: r.copy_neurons() if r.copies > 1 else np.arange(r.neurons[0], r.neurons[1])
              for r in low.populations if r.role == "hidden"}
    out = next(r for r in low.populations if r.role == "output")
    readout = [np.arange(r.neurons[0], r.neurons[1]) for r in low.populations if r.role == "readout"]
    return ChipTimeStudent(low.xylo_spec, steps, hidden, out.name, input_pad=low.timing.input_pad,
                           output_lag=low.timing.output_lag, shifts=low.timing.shifts, learn=learn, slope=slope,
                           unit=surrogate_units(low), unit_out=np.asarray(out.units, np.float64),
                           also_learned=np.concatenate(readout) if readout else (), fixed_output=out.method == "copy",
                           device=device)


def surrogate_units(low) -> np.ndarray:
    """Per hidden neuron, the chip units of one IR threshold (the lowering's gains; the chip threshold where no
    population is carried): the scale of the spike surrogate, so that a single-rule neuron, whose chip
    threshold is an offset near 2**14, gets a gradient as local as a direct one's."""
    spec = low.xylo_spec
    unit = np.asarray(spec.threshold, np.float64).copy()
    for r in low.populations:
        if r.role in ("hidden", "readout"):
            unit[r.neurons[0]:r.neurons[1]] = np.asarray(r.units, np.float64)
    return unit


def lowered_counts(low):
    """``(student, x) -> counts``: the student's exported spec run by the bit-exact emulator on the chip's window
    of ``x``, output counts over the model's steps."""
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.feed import chip_window, read_window

    def run(student, x: np.ndarray) -> np.ndarray:
        out = emulate(student.export(), chip_window(np.asarray(x), low.timing.input_pad, low.timing.output_lag))
        return read_window(out.output_spikes, low.timing.output_lag, x.shape[1]).sum(axis=1, dtype=np.int64)

    return run


def forward_equals_emulator(student, x: np.ndarray) -> str:
    """The student's forward pass (chip time, every hidden and output event) against the bit-exact emulator on
    the exported spec; a difference is an internal error."""
    import torch

    from snncc.targets.xylo.emulation.emulator import emulate

    like = student.core.dash_mem
    chip_x = student.chip_input(torch.as_tensor(np.asarray(x), dtype=like.dtype, device=like.device))
    with torch.no_grad():
        run = student.core(chip_x, record=True)
    em = emulate(student.export(), chip_x.cpu().numpy().astype(np.int64), record=True)
    mine = {"output_spikes": run.states["output_spikes"], "spikes": run.states["spikes"],
            "vmem": run.states["vmem"], "vmem_out": run.states["vmem_out"]}
    for name, value in mine.items():
        got = np.rint(value.cpu().numpy()).astype(np.int64)
        if not np.array_equal(got, np.asarray(getattr(em, name)).astype(np.int64)):
            raise InternalError(f"the fine-tuned spec's {name} in the emulator differs from the differentiable "
                                "forward pass it was trained with")
    return (f"the emulator equals the differentiable forward pass on the exported integers (output and hidden "
            f"events, membranes) on {x.shape[0]} held-out samples of {chip_x.shape[1]} chip steps")


def finetune_lowered(low, split, *, config=None, task_sets=(), progress=None,
                     learn=("weights", "thresholds", "biases"), slope: float = 5.0) -> XyloLoweredFinetuned:
    """Fine-tune the lowered spec of ``low`` (``lowering.lower.lower``) towards the graph as trained (``low.trained``,
    its own reset) on ``split``; the kept spec is checked against the forward pass and its twin rebuilt."""
    from snncc.targets.kit.finetuning import FinetuneConfig, finetune, resolve_device
    from snncc.targets.xylo.lowering.twin import spec_graph

    config = config or FinetuneConfig(lr=dict(XYLO_LR))
    device = resolve_device(config.device)
    steps = int(split.x.shape[1])
    student = lowered_student(low, steps, learn=learn, slope=slope, device=device)
    student, record = finetune(student, low.trained, split, config=config, deployed_counts=lowered_counts(low),
                               task_sets=list(task_sets), progress=progress)
    checked = forward_equals_emulator(student, split.x[split.held_out[:FORWARD_CHECK_SAMPLES]])
    spec = student.export()
    kwargs = spec.kwargs()
    tuned = dataclasses.replace(low, spec=kwargs, twin=spec_graph(kwargs, low.dt))
    if low.changes:
        record.notes.append("the teacher is the graph as trained (its own reset); Xylo runs it with reset by "
                            "subtraction (--allow-reset-change): the agreement includes the reset change")
    return XyloLoweredFinetuned(tuned, low, student, record, checked)


def with_finetune_record(artefact, result: XyloLoweredFinetuned):
    """``artefact`` (``artefact.write.build_artefact`` of the fine-tuned lowering) with manifest.json's ``finetune``
    entry (``kit.finetuned.finetune_entry``) and the forward-pass check under ``validation``."""
    from snncc.targets.kit.manifest import manifest_bytes
    from snncc.targets.xylo.artefact.format import MANIFEST

    manifest = dict(artefact.manifest)
    manifest["validation"] = {**manifest["validation"], "finetune": "checked: " + result.forward_check}
    manifest["finetune"] = finetune_entry(result.record)
    files = dict(artefact.files)
    files[MANIFEST] = manifest_bytes(manifest, default=float)
    notes = list(artefact.notes) + ["fine-tuned: spec.npz's weights, thresholds and biases trained through Xylo's "
                                    "integer arithmetic towards the float graph as trained (docs/finetune.md)"]
    return dataclasses.replace(artefact, files=files, manifest=manifest, notes=notes)


def finetune_artefact(graph: Graph, inputs, options: XyloOptions, finetuning, *, labels=None, data: str | None = None,
                      progress=None) -> FinetunedArtefact:
    """``target.finetune`` (``options``: the validated ``XyloOptions``; ``finetuning``: ``FinetuneOptions``): lower
    as ``compile`` does, fine-tune on the user's data or seeded random spikes, write and check as any artefact."""
    from snncc.targets.kit.finetuning import FinetuneConfig, model_split, resolve_device
    from snncc.targets.xylo.artefact.write import build_artefact
    from snncc.targets.xylo.chip import get_chip
    from snncc.targets.xylo.lowering import design_rules
    from snncc.targets.xylo.lowering.lower import lower

    if finetuning.finetune_out is not None:
        raise SnnccError(FINETUNE_OUT_REFUSAL, field="--finetune-out")
    device = finetuning.device or "cpu"
    resolve_device(device)                      # an unavailable device is refused before any work
    split = model_split(graph, inputs, labels, time_steps=options.time_steps, density=finetuning.density,
                        samples=finetuning.finetune_samples, seed=finetuning.finetune_seed, data=data)
    report = progress or (lambda done, total, phase: None)
    report(0, 1, "lowering and measuring the rules")
    if options.time_steps is None:
        options = dataclasses.replace(options, time_steps=int(split.x.shape[1]))
    try:
        low = lower(graph, options)
    except SnnccError as err:
        raise (err.with_file(options.source) if options.source else err) from None
    config = FinetuneConfig(epochs=finetuning.finetune_epochs, seed=finetuning.finetune_seed, device=device,
                            lr=dict(XYLO_LR))
    result = finetune_lowered(low, split, config=config, progress=progress)
    design_rules.check_spec(result.lowered.spec, get_chip(low.chip))
    report(0, 1, "writing and re-reading spec.npz")
    artefact = with_finetune_record(build_artefact(result.lowered, options.source), result)
    return FinetunedArtefact(artefact, result.record, refusal=FINETUNE_OUT_REFUSAL)
