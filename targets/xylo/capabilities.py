"""The registered Xylo target (SynSense Xylo Audio 2, Xylo IMU, Xylo Audio 3): its options record and
capabilities, each importing its work on use.

This module imports nothing heavy (not even numpy): listing or choosing the target is instant.

    lower    -> XyloArtefact  (lowering.py, package.py: spec.npz + manifest.json + README + board script)
    identify -> ArtefactIdentity (written.py: is this directory a Xylo artefact, from which model)
    check    -> XyloCheckRecord (check.py: the written artefact vs the float model on labelled data, loss by cause)
    agree    -> XyloCheckRecord (check.py: the same without labels: agreement per stage, the float ceiling)
    emulate  -> XyloEmulation (run_artefact.py: a written artefact on inputs, bit-exact, the manifest's feed)
    map      -> XyloUsage     (usage.py: neurons, synapses, fan-out against each chip's limits; real time)
    estimate -> XyloUsage     (usage.py: the same with event rates measured on the given inputs; no energy)
    hardware -> XyloHardware  (search_figures.py: a search trial's neurons used, feasibility, real-time margin)
    finetune -> XyloFinetunedArtefact (finetune.py: the lowered spec trained through Xylo Audio 2's integer
                arithmetic towards the float graph as trained; docs/finetune.md)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError
from snncc.progress import Progress as PhaseProgress
from snncc.targets.base import (
    AgreementOptions, Artefact, CoreMap, Emulation, FinetunedArtefact, FinetuneOptions, Given, HardwareCosts,
    Progress, Record, TargetOptions, capability_options, option, target_options,
)

if TYPE_CHECKING:
    import numpy as np

    from snncc.artefacts import ArtefactIdentity
    from snncc.ir.graph import Graph
    from snncc.targets.base import Model

CHIP_KEYS = ("syns61201", "syns63300", "syns65302")            # = chip.CHIPS (tested)
RULES = ("auto", "direct", "single", "single-identified", "relayed")   # = lowering.RULES (tested)
MODEL_VERBS = ("lower", "check", "agree", "map")
MAX_REPLICAS = 8                # = lowering.MAX_REPLICAS (tested)
RELAY_SETS = ("fast", "both")   # = lowering.RELAY_SETS (tested)
RANDOM_STEPS = 256                                             # steps of report's and agree's random samples
DEFAULT_AGREEMENT_SAMPLES = 1000                               # a 95 % interval of about +-0.03


@dataclass(frozen=True)
class XyloOptions(TargetOptions):
    """Xylo's options (each declared for the verbs that read it); ``seed`` (of the calibration inputs) is a
    setting no flag offers."""

    chip: str | None = option(
        "Xylo chip: 'syns61201' (Xylo Audio 2, default), 'syns63300' (Xylo IMU), 'syns65302' (Xylo Audio 3).",
        choices=CHIP_KEYS, rule=f"chip must be one of {', '.join(CHIP_KEYS)}", capabilities=MODEL_VERBS)
    rule: str | None = option(
        "Xylo placement rule: 'direct' (one chip neuron per neuron, nearest decays), 'single' (two synaptic "
        "currents fitted to the neuron's kernel, one spike per step), 'single-identified' (the same, weights fitted "
        "to the float graph's voltages), 'relayed' (the same with sigma-delta relay neurons adding a third kernel "
        "term), or 'auto' (default: each measured in snncc's emulator, the best kept).",
        choices=RULES, rule=f"rule must be one of {', '.join(RULES)}", capabilities=MODEL_VERBS)
    replicas: int | None = option(
        "Replicas of the hidden network, each fitted and rounded on its own calibration inputs (its relays a step "
        "coarser), the output neurons reading each with 1/K of the weights: the copies' rounding errors partly "
        "average out (costs K times the hidden neurons and their synaptic events). Default 1.",
        minimum=1, maximum=MAX_REPLICAS, rule=f"replicas must be a whole number from 1 to {MAX_REPLICAS}",
        capabilities=MODEL_VERBS)
    relays: str | None = option(
        "Relays of the relayed rule: 'fast' (default: one sigma-delta relay per presynaptic channel, at the faster "
        "synapse dash) or 'both' (two, one at each synapse dash: a finer kernel fit, fitted on 1024 calibration "
        "samples unless --calibration-samples says otherwise; costs a second relay neuron per channel, twice the "
        "relays' events and a lowering several times slower).",
        choices=RELAY_SETS, rule=f"relays must be one of {', '.join(RELAY_SETS)}", capabilities=MODEL_VERBS)
    allow_reset_change: bool = option(
        "Accept a model that resets to zero, deployed with reset by subtraction (Xylo's; snncc check measures the "
        "cost).", default=False, capabilities=("lower", "check", "agree"))
    time_steps: int | None = option("Steps of each seeded calibration sample (default 256).", minimum=1,
                                    rule="time steps must be a whole number >= 1", capabilities=("lower",))
    calibration_samples: int | None = option(
        "Seeded random calibration samples the rule is fitted and chosen on (default 256, 1024 with --relays both; "
        "SYNTHETIC).", minimum=2,
        rule="calibration samples must be a whole number >= 2", capabilities=("lower",))
    seed: int = 1


class XyloTarget:
    """Capabilities: lower, check, agree, emulate, map, estimate (report), hardware (hpo), finetune."""

    name = "xylo"
    description = "SynSense Xylo (Audio 2, IMU, Audio 3): spec.npz for XyloSim/samna, checked by a bit-exact emulator"
    output_kind = "directory"
    output_suffix = ".xylo"
    options_type = XyloOptions

    def _options(self, options: Given, capability: str) -> XyloOptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, XyloOptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.ir.graph import Graph
        from snncc.targets.xylo.lowering import lower, lowering_settings
        from snncc.targets.xylo.package import package

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("Xylo lowers IR graphs only (model_kinds)", field="--target")
        if progress is not None:
            progress(0, 2, "lowering and measuring the rules")
        try:
            low = lower(model, lowering_settings(opts))
        except SnnccError as err:          # a design rule broken by the model: name the model file
            raise (err.with_file(opts.source) if opts.source else err) from None
        if progress is not None:
            progress(1, 2, "writing and re-reading spec.npz")
        found: Artefact = package(low, opts.source)
        if progress is not None:
            progress(2, 2, "done")
        return found

    def identify(self, path: Path) -> ArtefactIdentity | None:
        from snncc.targets.xylo.written import identify_artefact

        found: ArtefactIdentity | None = identify_artefact(path)
        return found

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
              progress: Progress | None = None) -> Record:
        """The written artefact ``artefact`` (None: the one compile would write, in a temporary directory)
        against the float model on a labelled data set: accuracy and agreement per stage, loss by cause."""
        from snncc.targets.xylo.check import check_written, open_or_compile

        opts = self._options(options, "check")
        written, tmp = open_or_compile(graph, artefact, lambda: self.lower(graph, opts))
        try:
            what = f"{len(labels)} labelled samples of {data or 'the data set'}" + (" (SYNTHETIC)" if synthetic else "")
            found: Record = check_written(graph, written, inputs, labels, what)
        finally:
            if tmp is not None:
                tmp.cleanup()
        if progress is not None:
            progress(len(labels))
        return found

    def agree(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
              agreement: AgreementOptions | None = None, *, artefact: Path | None = None, data: str | None = None,
              progress: Progress | None = None) -> Record:
        """The written artefact's agreement with the float model without labels, per stage, with the float
        model's own ceiling under ``agreement.noise``; no inputs: seeded random spikes (SYNTHETIC)."""
        from snncc.targets.xylo.check import check_written, open_or_compile

        how = agreement or capability_options(AgreementOptions)
        opts = self._options(options, "agree")
        written, tmp = open_or_compile(graph, artefact, lambda: self.lower(graph, opts))
        try:
            if inputs is None:
                import numpy as np

                samples = how.samples or DEFAULT_AGREEMENT_SAMPLES
                x = (np.random.default_rng(0).random((samples, RANDOM_STEPS, written.spec.n_in))
                     < how.density).astype(np.uint8)
                what = (f"{samples} seeded random spike trains (density {how.density:g}, seed 0), {RANDOM_STEPS} steps "
                        "(SYNTHETIC)")
            else:
                x, what = inputs, f"{len(inputs)} samples of {data or 'the given inputs'} (no labels used)"
            found: Record = check_written(graph, written, x, None, what, noise=how.noise)
        finally:
            if tmp is not None:
                tmp.cleanup()
        if progress is not None:
            progress(int(len(x)))
        return found

    def emulate(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Emulation:
        from snncc.targets.xylo.run_artefact import emulate_artefact

        found: Emulation = emulate_artefact(bundle, inputs, record=record, stream=stream, gap=gap, source=source,
                                            progress=progress)
        return found

    def map(self, source: Path, options: Given = None) -> CoreMap:
        """A written artefact directory, or a model file lowered first with ``options``."""
        from snncc.targets.xylo.usage import usage_of_artefact
        from snncc.targets.xylo.written import read_manifest

        opts = self._options(options, "map")
        if read_manifest(source) is not None:
            if opts.chip is not None or opts.rule is not None:
                raise SnnccError("does not apply to a written artefact (compile fixed it)",
                                 field="--chip" if opts.chip is not None else "--rule")
            found: CoreMap = usage_of_artefact(source)
            return found
        return self._map_model(source, opts)

    def _map_model(self, source: Path, opts: XyloOptions) -> CoreMap:
        import tempfile

        from snncc.frontends import load_model
        from snncc.targets.xylo.usage import usage_of_artefact

        graph = load_model(source)
        with tempfile.TemporaryDirectory(prefix="snncc-xylo-map-") as tmp:
            path = Path(tmp) / "model.xylo"
            self.lower(graph, opts).write(path)
            found = usage_of_artefact(path)
        found.source = str(source)
        found.notes.append("the model file was lowered first (snncc compile --target xylo with the same options)")
        return found

    def estimate(self, source: Path, inputs: object, *, data: str | None = None, note: str = "",
                 limit: int | None = None, progress: Progress | None = None) -> Record:
        """Usage and real time with event rates measured on ``inputs`` in snncc's emulator; no energy figure."""
        import numpy as np

        from snncc.inputs import RandomSpikes
        from snncc.targets.xylo.usage import usage_on_inputs
        from snncc.targets.xylo.written import read_artefact

        if isinstance(inputs, RandomSpikes):
            x = inputs.draw(RANDOM_STEPS, read_artefact(source).spec.n_in)
            note = note or inputs.note()
        else:
            x = np.asarray(inputs)
        if limit is not None:
            x = x[:limit]
        found: Record = usage_on_inputs(source, x, note)
        if progress is not None:
            progress(int(x.shape[0]) if x.ndim == 3 else 1)
        return found

    def hardware(self) -> HardwareCosts:
        from snncc.targets.xylo.search_figures import XyloHardware

        return XyloHardware(self)

    def finetune(self, model: Model, inputs: np.ndarray | None, options: Given = None,
                 finetuning: FinetuneOptions | None = None, *, labels: np.ndarray | None = None,
                 data: str | None = None, progress: PhaseProgress | None = None) -> FinetunedArtefact:
        """Lower as ``lower`` does, then train the XyloSpec's weights, thresholds and biases through Xylo Audio 2's
        integer arithmetic towards the float graph as trained (no labels); ``--finetune-out`` is refused."""
        from snncc.ir.graph import Graph
        from snncc.targets.xylo.finetune import finetune_artefact

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("Xylo fine-tunes IR graphs only (model_kinds)", field="--finetune")
        found: FinetunedArtefact = finetune_artefact(model, inputs, opts,
                                                     finetuning or capability_options(FinetuneOptions),
                                                     labels=labels, data=data, progress=progress)
        return found


target = XyloTarget()
