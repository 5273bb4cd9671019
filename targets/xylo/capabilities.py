"""The registered Xylo target (SynSense Xylo Audio 2, Xylo IMU, Xylo Audio 3): its capabilities, each importing
its work on use; its option record is ``options.XyloOptions``.

This module imports nothing heavy (not even numpy): listing or choosing the target is instant.

    lower    -> XyloArtefact  (lowering/, artefact/write.py: spec.npz + manifest.json + README + board script)
    identify -> ArtefactIdentity (artefact/read.py: is this directory a Xylo artefact, from which model)
    check    -> CheckReport   (checks/stages.py: the written artefact vs the float model on labelled data, by cause)
    agree    -> CheckReport   (checks/stages.py: the same without labels: agreement per stage, the float ceiling)
    emulate  -> XyloEmulation (emulation/run_artefact.py: a written artefact on inputs, bit-exact, the manifest's feed)
    map      -> XyloUsage     (estimate/usage.py: neurons, synapses, fan-out against each chip's limits; real time)
    estimate -> XyloUsage     (estimate/usage.py: the same with event rates measured on the given inputs; no energy)
    hardware -> XyloHardware  (estimate/search_figures.py: a search trial's neurons, feasibility, real-time margin)
    finetune -> FinetunedArtefact (finetune/tuning.py: the lowered spec trained through Xylo Audio 2's integer
                arithmetic towards the float graph as trained; docs/finetune.md)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets.base import (
    AgreementOptions, Artefact, CoreMap, Emulation, FinetunedArtefact, FinetuneOptions, Given, HardwareCosts,
    Progress, Record, capability_options, target_options,
)
from snncc.targets.kit import SnnccError
from snncc.targets.kit import Progress as PhaseProgress
from snncc.targets.xylo.options import XyloOptions

if TYPE_CHECKING:
    import numpy as np

    from snncc.ir.graph import Graph
    from snncc.targets.base import Model
    from snncc.targets.kit.artefact import ArtefactIdentity

__all__ = ["XyloTarget", "XyloOptions", "target"]


class XyloTarget:
    """Capabilities: lower, check, agree, emulate, map, estimate (report), hardware (hpo), finetune."""

    name = "xylo"
    description = "SynSense Xylo (Audio 2, IMU, Audio 3): spec.npz for XyloSim/samna, checked by a bit-exact emulator"
    output_kind = "directory"
    output_suffix = ".xylo"
    options_type = XyloOptions

    def replace_refusal(self, path: str | Path) -> str | None:
        """Why an existing directory ``path`` may not be replaced by this target's artefact (None: it may)."""
        from snncc.targets.xylo.artefact.format import MANIFEST_FORMAT

        return MANIFEST_FORMAT.replace_refusal(path)

    def _options(self, options: Given, capability: str) -> XyloOptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, XyloOptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.ir.graph import Graph
        from snncc.targets.xylo.artefact.write import build_artefact
        from snncc.targets.xylo.lowering.lower import lower

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("Xylo lowers IR graphs only (model_kinds)", field="--target")
        if progress is not None:
            progress(0, 2, "lowering and measuring the rules")
        try:
            low = lower(model, opts)
        except SnnccError as err:          # a design rule broken by the model: name the model file
            raise (err.with_file(opts.source) if opts.source else err) from None
        if progress is not None:
            progress(1, 2, "writing and re-reading spec.npz")
        found: Artefact = build_artefact(low, opts.source)
        if progress is not None:
            progress(2, 2, "done")
        return found

    def identify(self, path: Path) -> ArtefactIdentity | None:
        from snncc.targets.xylo.artefact.read import identify_artefact

        found: ArtefactIdentity | None = identify_artefact(path)
        return found

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
              progress: Progress | None = None) -> Record:
        """The written artefact ``artefact`` (None: the one compile would write, in a temporary directory)
        against the float model on a labelled data set: accuracy and agreement per stage, loss by cause."""
        from snncc.targets.kit.measured import artefact_to_measure, described
        from snncc.targets.xylo.artefact.read import read_artefact
        from snncc.targets.xylo.checks.stages import check_written

        opts = self._options(options, "check")
        with artefact_to_measure(self, graph, opts, artefact) as path:
            what = f"{len(labels)} labelled samples of {data or 'the data set'}" + (" (SYNTHETIC)" if synthetic else "")
            found: Record = check_written(graph, read_artefact(path), inputs, labels, what,
                                          artefact=None if artefact is not None else described(None, path),
                                          progress=progress)
        return found

    def agree(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
              agreement: AgreementOptions | None = None, *, artefact: Path | None = None, data: str | None = None,
              progress: Progress | None = None) -> Record:
        """The written artefact's agreement with the float model without labels, per stage, with the float
        model's own ceiling under ``agreement.noise``; no inputs: seeded random spikes (SYNTHETIC)."""
        from snncc.targets.kit.agreement import default_samples, default_samples_note
        from snncc.targets.kit.measured import artefact_to_measure, described
        from snncc.targets.kit.reference import spiking_neurons
        from snncc.targets.kit.timebase import sample_steps
        from snncc.targets.xylo.artefact.read import read_artefact
        from snncc.targets.xylo.checks.stages import check_written

        how = agreement or capability_options(AgreementOptions)
        opts = self._options(options, "agree")
        with artefact_to_measure(self, graph, opts, artefact) as path:
            written = read_artefact(path)
            random = None
            if inputs is None:
                steps = written.sample_steps or sample_steps(graph, opts.time_steps)[0]
                samples = how.samples or default_samples(spiking_neurons(graph), steps)
                random = (samples, steps, how.density, 0)
                shown = f"{samples} samples" if how.samples else default_samples_note(samples)
                what = (f"{shown}: seeded random spike trains (density {how.density:g}, seed 0), {steps} steps "
                        "(SYNTHETIC)")
            else:
                what = f"{len(inputs)} samples of {data or 'the given inputs'} (no labels used)"
            found: Record = check_written(graph, written, inputs, None, what, noise=how.noise, random=random,
                                          artefact=None if artefact is not None else described(None, path),
                                          progress=progress)
        return found

    def emulate(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Emulation:
        from snncc.targets.xylo.emulation.run_artefact import emulate_artefact

        found: Emulation = emulate_artefact(bundle, inputs, record=record, stream=stream, gap=gap, source=source,
                                            progress=progress)
        return found

    def map(self, source: Path, options: Given = None) -> CoreMap:
        """A written artefact directory (``snncc map MODEL`` compiles the model first, as compile would)."""
        from snncc.targets.xylo.estimate.usage import usage_of_artefact

        opts = self._options(options, "map")
        given = [f for f in ("chip", "rule", "replicas", "relays") if getattr(opts, f) is not None]
        if given:
            raise SnnccError("does not apply to a written artefact (compile fixed it)",
                             field="--" + given[0].replace("_", "-"))
        found: CoreMap = usage_of_artefact(source)
        return found

    def estimate(self, source: Path, inputs: object, *, data: str | None = None, note: str = "",
                 limit: int | None = None, progress: Progress | None = None) -> Record:
        """Usage and real time with event rates measured on ``inputs`` in snncc's emulator; no energy figure."""
        import numpy as np

        from snncc.targets.kit.inputs import RandomSpikes
        from snncc.targets.kit.timebase import DEFAULT_TIME_STEPS
        from snncc.targets.xylo.artefact.read import read_artefact
        from snncc.targets.xylo.estimate.usage import usage_on_inputs

        if isinstance(inputs, RandomSpikes):
            written = read_artefact(source)
            x = inputs.draw(written.sample_steps or DEFAULT_TIME_STEPS, written.spec.n_in)
            note = note or inputs.note()
        else:
            x = np.asarray(inputs)
        if limit is not None:
            x = x[:limit]
        found: Record = usage_on_inputs(source, x, note)
        if progress is not None:
            progress(int(x.shape[0]) if x.ndim == 3 else 1)
        return found

    def profile(self, graph: Graph, artefact: Path, inputs: np.ndarray, *,
                progress: Progress | None = None) -> Record:
        """The chip's limits, real time at the inputs' event rates, NeuroBench (``estimate/profile.py``)."""
        from snncc.targets.xylo.estimate.profile import profile_artefact

        found: Record = profile_artefact(graph, artefact, inputs, progress)
        return found

    def hardware(self) -> HardwareCosts:
        from snncc.targets.xylo.estimate.search_figures import XyloHardware

        return XyloHardware(self)

    def finetune(self, model: Model, inputs: np.ndarray | None, options: Given = None,
                 finetuning: FinetuneOptions | None = None, *, labels: np.ndarray | None = None,
                 data: str | None = None, progress: PhaseProgress | None = None) -> FinetunedArtefact:
        """Lower as ``lower`` does, then train the XyloSpec's weights, thresholds and biases through Xylo Audio 2's
        integer arithmetic towards the float graph as trained (no labels); ``--finetune-out`` is refused."""
        from snncc.ir.graph import Graph
        from snncc.targets.xylo.finetune.tuning import finetune_artefact

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("Xylo fine-tunes IR graphs only (model_kinds)", field="--finetune")
        found: FinetunedArtefact = finetune_artefact(model, inputs, opts,
                                                     finetuning or capability_options(FinetuneOptions),
                                                     labels=labels, data=data, progress=progress)
        return found


target = XyloTarget()
