"""The registered C target: dependency-free C99 for microcontrollers, bit-exact with its emulator. Its options
record (``options.py``) and capabilities, each importing its work on use: this module imports nothing heavy
(not even numpy).

    lower     -> CArtefact   (lowering/lower.py: structure, weight rule given or measured, snn.c/snn.h + network.npz,
                              checked by reading the written network back)
    identify  -> ArtefactIdentity (artefact/written.py: is this directory a C artefact, from which model)
    check     -> CheckReport (checks/agreement.py: accuracy and agreement per stage on labelled data, loss by cause)
    agree     -> CheckReport (the same without labels; the float graph's own ceiling)
    emulate   -> CEmulation  (emulation/run_artefact.py: the bit-exact emulator of the C)
    run       -> CEmulation  (toolchain/run.py: the artefact's C built and run: host gcc, or Cortex-M4 in QEMU)
    map       -> CUsage      (estimate/report.py: flash and RAM against a part)
    estimate  -> CUsage      (the same plus instructions per step counted in QEMU; time, real time, energy ESTIMATE)
    hardware  -> CHardware   (estimate/search_figures.py: a search trial's flash, RAM, synaptic operations per step)
    profile   -> Profile     (estimate/profile.py: resources, real time and energy ESTIMATE, NeuroBench; snncc compare)
    finetune  -> FinetunedArtefact (finetune/: the integer network trained through its own arithmetic)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets.base import (
    AgreementOptions, Artefact, CoreMap, Emulation, FinetunedArtefact, FinetuneOptions, Given, HardwareCosts,
    Progress, Record, RunResult, capability_options, target_options,
)
from snncc.targets.c.options import COptions
from snncc.targets.kit import SnnccError
from snncc.targets.kit import Progress as PhaseProgress

if TYPE_CHECKING:
    import numpy as np

    from snncc.ir.graph import Graph
    from snncc.targets.base import Model
    from snncc.targets.kit.artefact import ArtefactIdentity

AGREEMENT_SEED = 0


class CTarget:
    """Capabilities: lower, identify, check, agree, emulate, run, map, estimate, hardware, profile, finetune."""

    name = "c"
    description = "C99 for microcontrollers (snn.c/snn.h, integer arithmetic), bit-exact with its emulator"
    output_kind = "directory"
    options_type = COptions

    def replace_refusal(self, path: str | Path) -> str | None:
        """Why an existing directory ``path`` may not be replaced by this target's artefact (None: it may)."""
        from snncc.targets.c.artefact.package import ARTEFACT

        return ARTEFACT.replace_refusal(path)

    def _options(self, options: Given, capability: str) -> COptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, COptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.ir.graph import Graph
        from snncc.targets.c.lowering.lower import lower_artefact

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("the C target lowers IR graphs only (model_kinds)", field="--target")
        found: Artefact = lower_artefact(model, opts, progress=progress)
        return found

    def identify(self, path: Path) -> ArtefactIdentity | None:
        from snncc.targets.c.artefact.written import identify_artefact

        return identify_artefact(path)

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
              progress: Progress | None = None) -> Record:
        """The written artefact (None: the one compile would write) against the float graph on labelled data."""
        from snncc.targets.c.checks.agreement import check_artefact
        from snncc.targets.kit.measured import artefact_to_measure

        opts = self._options(options, "check")
        what = f"{len(labels)} labelled samples of {data or 'the data set'}" + (" (SYNTHETIC)" if synthetic else "")
        with artefact_to_measure(self, graph, opts, artefact) as path:
            found: Record = check_artefact(graph, path, inputs, labels, what, progress=progress)
        return found

    def agree(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
              agreement: AgreementOptions | None = None, *, artefact: Path | None = None, data: str | None = None,
              progress: Progress | None = None) -> Record:
        """Agreement with the float graph without labels; no inputs: seeded random spikes (SYNTHETIC) of the
        artefact's own length, and the float graph's own ceiling under ``agreement.noise``."""
        from snncc.targets.c.checks.agreement import check_artefact
        from snncc.targets.c.artefact.written import open_artefact
        from snncc.targets.kit.agreement import default_samples, default_samples_note, random_inputs
        from snncc.targets.kit.measured import artefact_to_measure

        how = agreement or capability_options(AgreementOptions)
        opts = self._options(options, "agree")
        with artefact_to_measure(self, graph, opts, artefact) as path:
            if inputs is None:
                net = open_artefact(path).network
                samples = how.samples or default_samples(sum(p.n for p in net.populations), net.steps)
                x = random_inputs(samples, net.steps, net.inputs, how.density, AGREEMENT_SEED)
                shown = f"{samples}" if how.samples else default_samples_note(samples)
                what = (f"{shown} seeded random spike trains (density {how.density:g}, seed {AGREEMENT_SEED}), "
                        f"{net.steps} steps (SYNTHETIC)")
            else:
                x, what = inputs, f"{len(inputs)} samples of {data or 'the given inputs'} (no labels used)"
            found: Record = check_artefact(graph, path, x, None, what, noise=how.noise, progress=progress)
        return found

    def emulate(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Emulation:
        from snncc.targets.c.emulation.run_artefact import emulate_artefact

        found: Emulation = emulate_artefact(bundle, inputs, record=record, stream=stream, gap=gap, source=source,
                                            progress=progress)
        return found

    def run(self, artefact: Path, inputs: np.ndarray, *, source: str | None = None, stream: bool = False,
            backend: str = "auto") -> RunResult:
        """The artefact's C built and run: ``backend`` host (gcc), qemu (Cortex-M4 in QEMU) or auto."""
        from snncc.targets.c.toolchain.run import run_artefact

        found: RunResult = run_artefact(artefact, inputs, source=source, stream=stream, backend=backend)
        return found

    def map(self, source: Path, options: Given = None) -> CoreMap:
        """Flash and RAM of a written artefact against ``--mcu`` (default: the part compile recorded)."""
        from snncc.targets.c.artefact.written import identify_artefact
        from snncc.targets.c.estimate.report import usage_of_artefact

        opts = self._options(options, "map")
        if identify_artefact(source) is None:
            raise SnnccError("is not a C artefact directory; compile the model first (snncc compile MODEL --target c "
                             "-o DIR), then map DIR", file=str(source), field="source")
        found: CoreMap = usage_of_artefact(source, opts.mcu)
        return found

    def estimate(self, source: Path, inputs: object, *, data: str | None = None, note: str = "",
                 limit: int | None = None, progress: Progress | None = None) -> Record:
        """Memory, event rates, instructions per step counted in QEMU; time, real time and energy ESTIMATES."""
        import numpy as np

        from snncc.targets.c.artefact.written import open_artefact
        from snncc.targets.c.emulation.run_artefact import artefact_inputs
        from snncc.targets.c.estimate.report import estimate_artefact
        from snncc.targets.kit.inputs import RandomSpikes

        written = open_artefact(source)
        if isinstance(inputs, RandomSpikes):
            x = inputs.draw(written.network.steps, written.network.inputs)
            what = note or inputs.note()
        else:
            x, _ = artefact_inputs(written, np.asarray(inputs), data)
            what = note or f"{len(x)} samples of {data or 'the given inputs'}"
        if limit is not None:
            x = x[:limit]
        found: Record = estimate_artefact(source, x, what)
        if progress is not None:
            progress(int(x.shape[0]))
        return found

    def profile(self, graph: Graph, artefact: Path, inputs: np.ndarray, *,
                progress: Progress | None = None) -> Record:
        """Flash, RAM, neurons, synapses against the part; real time and energy from instructions counted in QEMU
        (ESTIMATE); NeuroBench's metrics from the artefact's synapses and its emulation (``estimate/profile.py``)."""
        from snncc.targets.c.estimate.profile import profile_artefact

        found: Record = profile_artefact(graph, artefact, inputs, progress)
        return found

    def hardware(self) -> HardwareCosts:
        from snncc.targets.c.estimate.search_figures import CHardware

        return CHardware(self)

    def finetune(self, model: Model, inputs: np.ndarray | None, options: Given = None,
                 finetuning: FinetuneOptions | None = None, *, labels: np.ndarray | None = None,
                 data: str | None = None, progress: PhaseProgress | None = None) -> FinetunedArtefact:
        """Lower as ``lower`` does, then train the integer network's weights, thresholds and biases through its
        own arithmetic towards the float graph as trained (no labels)."""
        from snncc.ir.graph import Graph
        from snncc.targets.c.finetune.tune import finetune_artefact

        opts = self._options(options, "lower")
        if not isinstance(model, Graph):
            raise SnnccError("the C target fine-tunes IR graphs only (model_kinds)", field="--finetune")
        found: FinetunedArtefact = finetune_artefact(model, inputs, opts,
                                                     finetuning or capability_options(FinetuneOptions),
                                                     labels=labels, data=data, progress=progress)
        return found


target = CTarget()
