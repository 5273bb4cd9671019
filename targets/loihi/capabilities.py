"""The registered Loihi target: its options record and capabilities, each importing its work on use.

This module imports nothing heavy, so listing or choosing the target, and verbs that only read,
map, emulate or estimate a bundle, never load the compiler's torch-based reference simulator.

The options record and its constants are ``options.py``'s; each capability receives the validated
``LoihiOptions`` record and hands it on as it is.

    lower      -> LoihiArtefact   (lowering/lower.py: timing, quantization, bundle checked by the emulator)
    identify   -> ArtefactIdentity (bundle/identify.py: is this file a Loihi bundle, from which model)
    check      -> CheckReport     (checks/accuracy.py: accuracy the written bundle loses on labelled data, and why)
    agree      -> CheckReport     (checks/agreement.py: the written bundle's agreement with the float model)
    emulate    -> BundleEmulation (emulation/run_bundle.py: a bundle on 0/1 inputs, bit-exact)
    map        -> CoreMap         (mapping/partition.py: a written bundle's populations on cores under every limit)
    estimate   -> EnergyReport    (estimate/report.py: ESTIMATE of energy and delay per sample)
    hardware   -> LoihiHardware   (estimate/search_figures.py: a search trial's cores, energy, delay)
    arithmetic -> LoihiArithmetic (arithmetic/straight_through.py: the quantization in torch, for QAT)
    finetune   -> FinetunedArtefact (finetune/: the lowered registers trained through the chip's integer
                  arithmetic, finetune/differentiable.py, towards the float graph as trained)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets.base import (
    AgreementOptions, Arithmetic, Artefact, CoreMap, Emulation, FinetunedArtefact, FinetuneOptions, Given,
    HardwareCosts, Progress, Record, capability_options, target_options,
)
from snncc.targets.kit import Progress as PhaseProgress
from snncc.targets.kit import SnnccError
from snncc.targets.loihi.options import LoihiOptions

if TYPE_CHECKING:
    import numpy as np

    from snncc.ir.graph import Graph
    from snncc.targets.base import Model
    from snncc.targets.kit.artefact import ArtefactIdentity



class LoihiTarget:
    name = "loihi"
    description = "Intel Loihi 1: HDF5 bundle (netx layout) checked by a bit-exact emulator"
    output_kind = "file"
    output_suffix = ".net"
    options_type = LoihiOptions

    def _options(self, options: Given, capability: str | tuple[str, ...]) -> LoihiOptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, LoihiOptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.ir.graph import Graph
        from snncc.targets.loihi.lowering.lower import lower_artefact

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("Loihi lowers IR graphs only (model_kinds)", field="--target")
        found: Artefact = lower_artefact(model, opts, progress=progress)
        return found

    def identify(self, path: Path) -> ArtefactIdentity | None:
        from snncc.targets.loihi.bundle.identify import identify_bundle

        return identify_bundle(path)

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
              progress: Progress | None = None) -> Record:
        """The written bundle ``artefact`` (None: the one compile would write, in a temporary directory)."""
        from snncc.targets.kit.measured import artefact_to_measure
        from snncc.targets.loihi.checks.accuracy import check_bundle

        opts = self._options(options, ("check", "lower") if artefact is None else "check")
        with artefact_to_measure(self, graph, opts, artefact) as path:
            found: Record = check_bundle(graph, path, inputs, labels, opts, data=data, synthetic=synthetic,
                                         progress=progress)
        return found

    def agree(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
              agreement: AgreementOptions | None = None, *, artefact: Path | None = None, data: str | None = None,
              progress: Progress | None = None) -> Record:
        """Agreement of the written bundle ``artefact`` (None: the one compile would write) with the float model."""
        from snncc.targets.kit.measured import artefact_to_measure
        from snncc.targets.loihi.checks.agreement import agree_bundle

        opts = self._options(options, ("agree", "lower") if artefact is None else "agree")
        how = agreement or capability_options(AgreementOptions)
        with artefact_to_measure(self, graph, opts, artefact) as path:
            found: Record = agree_bundle(graph, path, inputs, how, data=data, progress=progress)
        return found

    def emulate(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Emulation:
        from snncc.targets.loihi.bundle.read import read_bundle
        from snncc.targets.loihi.emulation.run_bundle import emulate_bundle

        found: Emulation = emulate_bundle(read_bundle(bundle), inputs, record=record, stream=stream, gap=gap,
                                          source=source, progress=progress)
        return found

    def map(self, source: Path, options: Given = None) -> CoreMap:
        """The core map of the written bundle ``source`` (``snncc map MODEL`` compiles the model first)."""
        from snncc.targets.loihi.mapping.partition import map_bundle

        found: CoreMap = map_bundle(source, self._options(options, "map"))
        return found

    def estimate(self, source: Path, inputs: object, *, data: str | None = None, note: str = "",
                 limit: int | None = None, progress: Progress | None = None) -> Record:
        from snncc.targets.loihi.estimate.report import estimate_bundle

        found: Record = estimate_bundle(source, inputs, data=data, note=note, limit=limit, progress=progress)
        return found

    def profile(self, graph: Graph, artefact: Path, inputs: np.ndarray, *,
                progress: Progress | None = None) -> Record:
        """Cores, real time and energy ESTIMATE at the inputs' event rates, NeuroBench (``estimate/profile.py``)."""
        from snncc.targets.loihi.estimate.profile import profile_bundle

        found: Record = profile_bundle(graph, artefact, inputs, progress)
        return found

    def hardware(self) -> HardwareCosts:
        from snncc.targets.loihi.estimate.search_figures import LoihiHardware

        return LoihiHardware(self)

    def finetune(self, model: Model, inputs: np.ndarray | None, options: Given = None,
                 finetuning: FinetuneOptions | None = None, *, labels: np.ndarray | None = None,
                 data: str | None = None, progress: PhaseProgress | None = None) -> FinetunedArtefact:
        from snncc.ir.graph import Graph
        from snncc.targets.loihi.finetune.artefact import finetune_artefact

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("Loihi fine-tunes IR graphs only (model_kinds)", field="--finetune")
        found: FinetunedArtefact = finetune_artefact(model, inputs, opts,
                                                     finetuning or capability_options(FinetuneOptions),
                                                     labels=labels, data=data, progress=progress)
        return found

    def arithmetic(self, options: Given = None) -> Arithmetic:
        from snncc.targets.loihi.arithmetic.straight_through import LoihiArithmetic

        self._options(options, "lower")
        return LoihiArithmetic()


target = LoihiTarget()
