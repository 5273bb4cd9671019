"""The registered Jetson target: its options record and capabilities, each importing its work on use.

This module imports nothing heavy: listing or choosing the target loads neither torch nor ONNX.

    lower  -> JetsonArtefact     (lower.py: ONNX sequence + step models validated in ONNX Runtime;
                                  buffered.py for a buffered classifier, which has no IR graph)
    check  -> JetsonCheckRecord  (lower.py, check.py: the IR reference vs the artefact on a data set)
    run    -> RunResult          (run_artefact.py: an artefact on inputs, TensorRT or ONNX Runtime)
    bench  -> BenchRecord / LatencyComparison (bench_artefacts.py: the paper's latency and power protocol)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.progress import Progress as PhaseProgress
from snncc.targets.base import Artefact, Given, Progress, Record, RunResult, TargetOptions, option, target_options

if TYPE_CHECKING:
    import numpy as np

    from snncc.ir.graph import Graph
    from snncc.targets.base import Model


@dataclass(frozen=True)
class JetsonOptions(TargetOptions):
    """Jetson's options; ``seed`` (of the validation inputs) is a setting no flag offers."""

    jetpack: str | None = option(
        "JetPack version of the board (default 4.6); selects the ONNX opset (4.6 -> 13, 5.x/6.0 -> 17, "
        "6.1/6.2 -> 20).", capabilities=("lower",))
    time_steps: int | None = option("T of the unrolled sequence model (default: recording length / dt).",
                                    minimum=1, rule="time steps must be a whole number >= 1", capabilities=("lower",))
    seed: int = 0


class JetsonTarget:
    """Capabilities: lower, check (IR vs ONNX Runtime on data), run (an artefact on inputs), bench
    (the paper's latency and power protocol)."""

    name = "jetson"
    description = "NVIDIA Jetson: ONNX (sequence + streaming step) + TensorRT recipe, validated in ONNX Runtime"
    output_kind = "directory"
    options_type = JetsonOptions
    model_kinds = ("graph", "buffered")

    def _options(self, options: Given, capability: str) -> JetsonOptions:
        opts = target_options(self, options, capability)
        assert isinstance(opts, JetsonOptions)
        return opts

    def lower(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        from snncc.frontends.buffered import BufferedModel

        settings = self._options(options, "lower").as_dict()
        if isinstance(model, BufferedModel):
            from snncc.targets.jetson.buffered import lower_buffered

            buffered: Artefact = lower_buffered(model, settings, progress)
            return buffered
        from snncc.targets.jetson.lower import lower_graph

        found: Artefact = lower_graph(model, settings, progress)
        return found

    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
              data: str | None = None, synthetic: bool = False, progress: Progress | None = None) -> Record:
        """IR reference vs the ONNX Runtime artefact on a data set (``lower.check_graph``)."""
        from snncc.targets.jetson.lower import check_graph

        found: Record = check_graph(graph, inputs, labels, self._options(options, "check").as_dict(), data=data,
                                    synthetic=synthetic, progress=progress)
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
        from snncc.errors import SnnccError
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
