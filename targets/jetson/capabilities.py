"""The registered Jetson target: its options record and capabilities, each importing its work on use.

This module imports nothing heavy: listing or choosing the target loads neither torch nor ONNX.

    lower  -> JetsonArtefact     (lower.py: ONNX sequence + step models validated in ONNX Runtime;
                                  buffered.py for a buffered classifier, which has no IR graph)
    identify -> ArtefactIdentity (written.py: is a directory a Jetson artefact, from which model)
    check  -> CheckReport        (lower.py, check.py: the written artefact vs the IR reference on a data set)
    agree  -> CheckReport        (lower.py, check.py: the same without labels, random or given inputs)
    run    -> RunResult          (run_artefact.py: an artefact on inputs, TensorRT or ONNX Runtime)
    bench  -> BenchRecord / LatencyComparison (bench_artefacts.py: the paper's latency and power protocol)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets.kit import Progress as PhaseProgress
from snncc.targets.base import (
    AgreementOptions, Artefact, Given, Progress, Record, RunResult, capability_options, target_options,
)
from snncc.targets.jetson.options import JetsonOptions

if TYPE_CHECKING:
    import numpy as np

    from snncc.targets.kit.artefact import ArtefactIdentity
    from snncc.ir.graph import Graph
    from snncc.targets.base import Model


class JetsonTarget:
    """Capabilities: lower, identify (is a directory a Jetson artefact), check (the written artefact vs
    the IR on labelled data), agree (the same without labels), run (an artefact on inputs), bench (the
    paper's latency and power protocol)."""

    name = "jetson"
    description = "NVIDIA Jetson: ONNX (sequence + streaming step) + TensorRT recipe, validated in ONNX Runtime"
    output_kind = "directory"
    options_type = JetsonOptions
    model_kinds = ("graph", "buffered")

    def replace_refusal(self, path: str | Path) -> str | None:
        """Why an existing directory ``path`` may not be replaced by this target's artefact (None: it may)."""
        from snncc.targets.jetson.artefact_format import JETSON_FORMAT

        return JETSON_FORMAT.replace_refusal(path)

    def _options(self, options: Given, capability: str) -> JetsonOptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, JetsonOptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.targets.kit.models import BufferedModel

        settings = self._options(options, "lower")
        if isinstance(model, BufferedModel):
            from snncc.targets.jetson.buffered import lower_buffered

            buffered: Artefact = lower_buffered(model, settings, progress)
            return buffered
        from snncc.targets.jetson.lower import lower_graph

        found: Artefact = lower_graph(model, settings, progress)
        return found

    def identify(self, path: Path) -> ArtefactIdentity | None:
        from snncc.targets.jetson.written import identify_directory

        return identify_directory(path)

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
              progress: Progress | None = None) -> Record:
        """The written artefact ``artefact`` (None: the one compile would write, in a temporary directory)
        vs the IR reference on a data set (``lower.check_graph``)."""
        from snncc.targets.jetson.lower import check_graph
        from snncc.targets.kit.measured import artefact_to_measure

        settings = self._options(options, "check")
        with artefact_to_measure(self, graph, settings, artefact) as path:
            found: Record = check_graph(graph, inputs, labels, artefact=path, data=data, synthetic=synthetic,
                                        progress=progress)
        return found

    def agree(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
              agreement: AgreementOptions | None = None, *, artefact: Path | None = None, data: str | None = None,
              progress: Progress | None = None) -> Record:
        """The written artefact's agreement with the float model without labels (``lower.agree_graph``), with
        the float graph's own ceiling under ``agreement.noise``."""
        from snncc.targets.jetson.lower import agree_graph
        from snncc.targets.kit.measured import artefact_to_measure

        how = agreement or capability_options(AgreementOptions)
        settings = self._options(options, "agree")
        with artefact_to_measure(self, graph, settings, artefact) as path:
            found: Record = agree_graph(graph, inputs, artefact=path, samples=how.samples, density=how.density,
                                        noise=how.noise, data=data, progress=progress)
        return found

    def profile(self, graph: Graph, artefact: Path, inputs: np.ndarray, *,
                progress: Progress | None = None) -> Record:
        """Parameters and file sizes, and NeuroBench's metrics (``profile.py``); no real-time or energy estimate."""
        from snncc.targets.jetson.profile import profile_artefact

        found: Record = profile_artefact(graph, artefact, inputs, progress)
        return found

    def run(self, artefact: Path, inputs: np.ndarray, *, source: str | None = None, stream: bool = False,
            backend: str = "auto") -> RunResult:
        from snncc.targets.jetson.run_artefact import run_artefact

        found: RunResult = run_artefact(artefact, inputs, source=source, stream=stream, backend=backend)
        return found

    def bench(self, artefacts: list[Path], *, data: Path | None = None, samples: int = 64, power: bool = False,
              power_root: Path = Path("/"), rail: str = "VDD_IN", repeats: int = 3, warmup_passes: int = 6,
              timed_passes: int = 6, stream: bool = False, backend: str = "auto",
              progress: PhaseProgress | None = None) -> Record:
        """One artefact: a ``BenchRecord`` (with power); several: a ``LatencyComparison`` (ratios to the first)."""
        from snncc.targets.kit import SnnccError
        from snncc.targets.jetson.bench_artefacts import bench_many, bench_one

        if len(artefacts) > 1:
            if power:
                raise SnnccError("power is sampled for one artefact at a time", field="--power")
            many: Record = bench_many(artefacts, data=data, samples=samples, repeats=repeats,
                                      warmup_passes=warmup_passes, timed_passes=timed_passes, stream=stream,
                                      backend=backend, progress=progress)
            return many
        one: Record = bench_one(artefacts[0], data=data, samples=samples, power=power, power_root=power_root,
                                rail=rail, repeats=repeats, warmup_passes=warmup_passes, timed_passes=timed_passes,
                                stream=stream, backend=backend, progress=progress)
        return one


target = JetsonTarget()
