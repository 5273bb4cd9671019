"""The registered Loihi target: its options record and capabilities, each importing its work on use.

This module imports nothing heavy, so listing or choosing the target, and verbs that only read,
map, emulate or estimate a bundle, never load the compiler's torch-based reference simulator.

    lower      -> LoihiArtefact   (lowering/lower.py: timing, quantization, bundle checked by the emulator)
    identify   -> ArtefactIdentity (bundle/identify.py: is this file a Loihi bundle, from which model)
    check      -> CheckRecord     (checks/accuracy.py: accuracy the written bundle loses on labelled data, and why)
    agree      -> AgreementRecord (checks/agreement.py: the written bundle's agreement with the float model)
    emulate    -> BundleEmulation (emulation/run_bundle.py: a bundle on 0/1 inputs, bit-exact)
    map        -> CoreMap         (mapping/partition.py: populations placed on cores under every limit)
    estimate   -> EnergyReport    (estimate/report.py: ESTIMATE of energy and delay per sample)
    hardware   -> LoihiHardware   (estimate/search_figures.py: a search trial's cores, energy, delay)
    arithmetic -> LoihiArithmetic (arithmetic/straight_through.py: the quantization in torch, for QAT)
    finetune   -> LoihiFinetunedArtefact (finetune.py: the lowered registers trained through the chip's
                  integer arithmetic, lowering/differentiable.py, towards the float graph as trained)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError
from snncc.progress import Progress as PhaseProgress
from snncc.targets.base import (
    AgreementOptions, Arithmetic, Artefact, CoreMap, Emulation, FinetunedArtefact, FinetuneOptions, Given,
    HardwareCosts, Progress, Record, TargetOptions, capability_options, option, target_options,
)

if TYPE_CHECKING:
    import numpy as np

    from snncc.artefacts import ArtefactIdentity
    from snncc.ir.graph import Graph
    from snncc.targets.base import Model

MODEL_VERBS = ("lower", "check", "agree", "map")   # map lowers a model file first
TIMINGS = ("exact", "paper")                       # = lowering/timing.py's TIMINGS (tested)
SCALE_RULES = ("auto", "global", "per-layer", "split", "fine")   # = lowering/quantize.py's (tested)


@dataclass(frozen=True)
class LoihiOptions(TargetOptions):
    """Loihi's options (each declared for the verbs that read it)."""

    timing: str | None = option(
        "Timing: 'exact' (default) lowers the IR's delays and refractory period; 'paper' reproduces the "
        "authors' export (refDelay 1, no delays).", choices=TIMINGS, rule=f"timing must be one of {TIMINGS}",
        capabilities=MODEL_VERBS)
    scale: str | None = option(
        "Weight scale rule: 'global' (the paper's), 'per-layer', 'split' (per-layer, outlier weights in a "
        "second synapse format with a coarser exponent), 'fine' (each synapse its finest exponent), or 'auto' "
        "(default: the paper's unless outliers make it lossy; then the candidate with the smallest measured error).",
        choices=SCALE_RULES, rule="scale must be one of global, per-layer, split, fine, auto", capabilities=MODEL_VERBS)
    replicas: int | None = option(
        "Precision by replication: K relays per input channel and K copies of every hidden neuron, each weight "
        "split over K synapses (exact in float; K times finer weight steps at per-neuron scales, e.g. with "
        "--finetune; costs neurons, synapses and one step of latency). Default 1.",
        minimum=1, maximum=16, rule="replicas must be a whole number from 1 to 16", capabilities=MODEL_VERBS)
    allow_reset_change: bool = option(
        "Accept a subtract-reset model deployed with reset to zero (snncc check reports the cost).",
        default=False, capabilities=("lower", "check", "agree"))
    stream: bool = option("The paper's protocol, one stream with 100 blank steps between samples.",
                          default=False, capabilities=("check",))
    time_steps: int | None = option("tSample (default: the model's recording length / dt, else 100).",
                                    minimum=1, rule="time steps must be a whole number >= 1", capabilities=("lower",))


def _settings(options: LoihiOptions, **extra: object) -> dict[str, object]:
    """The options as the plain settings mapping the lowering functions read (``lower_model``)."""
    return {**options.as_dict(), **extra}


class LoihiTarget:
    name = "loihi"
    description = "Intel Loihi 1: HDF5 bundle (netx layout) checked by a bit-exact emulator"
    output_kind = "file"
    output_suffix = ".net"
    options_type = LoihiOptions

    def _options(self, options: Given, capability: str) -> LoihiOptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, LoihiOptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.ir.graph import Graph
        from snncc.targets.loihi.lowering.lower import lower_artefact

        settings = _settings(self._options(options, "lower"))
        if not isinstance(model, Graph):
            raise SnnccError("Loihi lowers IR graphs only (model_kinds)", field="--target")
        found: Artefact = lower_artefact(model, settings, progress=progress)
        return found

    def identify(self, path: Path) -> ArtefactIdentity | None:
        from snncc.targets.loihi.bundle.identify import identify_bundle

        return identify_bundle(path)

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
              progress: Progress | None = None) -> Record:
        """The written bundle ``artefact`` (None: the one compile would write, in a temporary directory)."""
        from snncc.targets.loihi.checks.accuracy import check_bundle, check_model
        from snncc.targets.loihi.checks.written import open_bundle

        opts = self._options(options, "check")
        settings = _settings(opts, data=data, synthetic=synthetic, mode="stream" if opts.stream else "batch")
        if artefact is None:
            found: Record = check_model(graph, inputs, labels, settings, progress=progress)
            return found
        written: Record = check_bundle(graph, open_bundle(artefact, graph), inputs, labels, settings,
                                       progress=progress)
        return written

    def agree(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
              agreement: AgreementOptions | None = None, *, artefact: Path | None = None, data: str | None = None,
              progress: Progress | None = None) -> Record:
        """Agreement of the written bundle ``artefact`` (None: the one compile would write) with the float model."""
        from snncc.targets.loihi.checks.agreement import measure_agreement, measure_bundle
        from snncc.targets.loihi.checks.written import open_bundle

        how = agreement or capability_options(AgreementOptions)
        if artefact is None:
            settings = _settings(self._options(options, "agree"), data=data)
            found: Record = measure_agreement(graph, settings, inputs, samples=how.samples, density=how.density,
                                              noise=how.noise, progress=progress)
            return found
        written: Record = measure_bundle(graph, open_bundle(artefact, graph), inputs, samples=how.samples,
                                         density=how.density, noise=how.noise, data=data, progress=progress)
        return written

    def emulate(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Emulation:
        from snncc.targets.loihi.bundle.hdf5 import read_bundle
        from snncc.targets.loihi.emulation.run_bundle import emulate_bundle

        found: Emulation = emulate_bundle(read_bundle(bundle), inputs, record=record, stream=stream, gap=gap,
                                          source=source, progress=progress)
        return found

    def map(self, source: Path, options: Given = None) -> CoreMap:
        from snncc.targets.loihi.bundle.load import load_network
        from snncc.targets.loihi.mapping.partition import map_network

        opts = self._options(options, "map")
        network = load_network(source, opts.timing, opts.scale, opts.replicas)
        try:
            found: CoreMap = map_network(network)
        except SnnccError as err:
            raise err.with_file(str(source)) from None
        return found

    def estimate(self, source: Path, inputs: object, *, data: str | None = None, note: str = "",
                 limit: int | None = None, progress: Progress | None = None) -> Record:
        from snncc.targets.loihi.estimate.report import estimate_bundle

        found: Record = estimate_bundle(source, inputs, data=data, note=note, limit=limit, progress=progress)
        return found

    def hardware(self) -> HardwareCosts:
        from snncc.targets.loihi.estimate.search_figures import LoihiHardware

        return LoihiHardware(self)

    def finetune(self, model: Model, inputs: np.ndarray | None, options: Given = None,
                 finetuning: FinetuneOptions | None = None, *, labels: np.ndarray | None = None,
                 data: str | None = None, progress: PhaseProgress | None = None) -> FinetunedArtefact:
        from snncc.ir.graph import Graph
        from snncc.targets.loihi.finetune import finetune_artefact

        settings = _settings(self._options(options, "lower"))
        if not isinstance(model, Graph):
            raise SnnccError("Loihi fine-tunes IR graphs only (model_kinds)", field="--finetune")
        found: FinetunedArtefact = finetune_artefact(model, inputs, settings,
                                                     finetuning or capability_options(FinetuneOptions),
                                                     labels=labels, data=data, progress=progress)
        return found

    def arithmetic(self, options: Given = None) -> Arithmetic:
        from snncc.targets.loihi.arithmetic.straight_through import LoihiArithmetic

        self._options(options, "lower")
        return LoihiArithmetic()


target = LoihiTarget()
