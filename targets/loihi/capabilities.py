"""The registered Loihi target: its options record and capabilities, each importing its work on use.

This module imports nothing heavy, so verbs that only read, map, emulate or estimate a bundle
never load the compiler's torch-based reference simulator.

    lower     -> LoihiArtefact (lowering/lower.py: timing, quantization, bundle checked by the emulator)
    check     -> CheckRecord   (checks/accuracy.py: accuracy lost on a labelled data set, and why)
    agree     -> AgreementRecord (checks/agreement.py: agreement with the float graph, no labels)
    emulate   -> BundleEmulation (emulation/run_bundle.py: a bundle on 0/1 inputs, bit-exact)
    map       -> CoreMap       (mapping/partition.py: populations placed on cores under every limit)
    estimate  -> EnergyReport  (estimate/report.py: ESTIMATE of energy and delay per sample)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from snncc.targets.base import LoihiOptions, Progress, TargetOptions, target_options


def _settings(options: LoihiOptions, **extra) -> dict[str, Any]:
    """The options as the plain settings mapping the lowering functions read (``lower_model``)."""
    return {**options.as_dict(), **extra}


class LoihiTarget:
    name = "loihi"
    description = "Intel Loihi 1: HDF5 bundle (netx layout) checked by a bit-exact emulator"
    output_kind = "file"
    output_suffix = ".net"
    options_type = LoihiOptions

    def lower(self, graph, options: TargetOptions | Mapping[str, Any] | None = None, *,
              progress: Progress | None = None):
        from snncc.targets.loihi.lowering.lower import lower_artefact

        return lower_artefact(graph, _settings(target_options(self, options)))

    def check(self, graph, inputs, labels, options: TargetOptions | Mapping[str, Any] | None = None, *,
              data: str | None = None, synthetic: bool = False, progress: Progress | None = None):
        from snncc.targets.loihi.checks.accuracy import check_model

        opts = target_options(self, options)
        settings = _settings(opts, data=data, synthetic=synthetic, mode="stream" if opts.stream else "batch")
        return check_model(graph, inputs, labels, settings, progress=progress)

    def agree(self, graph, inputs, options: TargetOptions | Mapping[str, Any] | None = None, *,
              data: str | None = None, samples: int = 40, density: float = 0.08, noise: float = 0.01):
        from snncc.targets.loihi.checks.agreement import measure_agreement

        settings = _settings(target_options(self, options), data=data)
        return measure_agreement(graph, settings, inputs, samples=samples, density=density, noise=noise)

    def emulate(self, bundle: Path, inputs, *, record: str = "outputs", stream: bool = False, gap: int | None = None,
                source: str | None = None, progress: Progress | None = None):
        from snncc.targets.loihi.bundle.hdf5 import read_bundle
        from snncc.targets.loihi.emulation.run_bundle import emulate_bundle

        return emulate_bundle(read_bundle(bundle), inputs, record=record, stream=stream, gap=gap, source=source,
                              progress=progress)

    def map(self, source: Path, options: TargetOptions | Mapping[str, Any] | None = None):
        from snncc.errors import SnnccError
        from snncc.targets.loihi.mapping.partition import map_network
        from snncc.targets.loihi.bundle.load import load_network

        given = options.as_dict() if isinstance(options, TargetOptions) else dict(options or {})
        network = load_network(source, given.get("timing"), given.get("scale"))
        try:
            return map_network(network)
        except SnnccError as err:
            raise err.with_file(str(source)) from None

    def estimate(self, source: Path, inputs, *, data: str | None = None, note: str = "", limit: int | None = None,
                 progress: Progress | None = None):
        from snncc.targets.loihi.estimate.report import estimate_bundle

        return estimate_bundle(source, inputs, data=data, note=note, limit=limit, progress=progress)


target = LoihiTarget()
