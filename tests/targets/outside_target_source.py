"""An out-of-tree target, written as a third party would write one: it imports from snncc only the interface
(``snncc.targets.base``), the kit (``snncc.targets.kit``) and the IR it is handed (``snncc.ir``);
``tests/targets/test_outside_target.py`` installs it from a temporary ``*.dist-info`` and fails if it imports
anything else.

The "float32 target": the validated graph written as a manifest directory (``graph.snnir`` + ``manifest.json``,
the kit's ``ManifestFormat``), run in float32 by the IR reference (its emulator), checked against the float64
graph (the kit's ``CheckReport``: one stage, cause "other"). Options: ``--f32-chunk`` (samples per run).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from snncc.targets.base import AgreementOptions, TargetOptions, capability_options, option, target_options
from snncc.targets.kit import SNNCC_VERSION, SnnccError
from snncc.targets.kit.agreement import argmax_agreement, count_correlation, random_inputs
from snncc.targets.kit.artefact import model_record, sha256_bytes
from snncc.targets.kit.checks import accuracy_pair, ceiling_record, report_from, stage
from snncc.targets.kit.emulation import OutputSpikes
from snncc.targets.kit.inputs import check_batch
from snncc.targets.kit.manifest import ManifestFormat, manifest_bytes, source_identity
from snncc.targets.kit.measured import artefact_to_measure
from snncc.targets.kit.reference import float_counts, noise_ceiling, readout_population
from snncc.targets.kit.timebase import sample_steps

GRAPH = "graph.snnir"
FORMAT = ManifestFormat(format="snncc-float32-artefact", target="f32", kind="a float32 test artefact",
                        describe=lambda manifest: "float32 test artefact (graph.snnir)")


@dataclass(frozen=True)
class F32Options(TargetOptions):
    f32_chunk: int | None = option("Samples per float32 run (default 64).", minimum=1,
                                   capabilities=("lower", "check", "agree"))
    time_steps: int | None = option("Steps of each random sample (default: the time base).", minimum=1,
                                    capabilities=("lower",))


@dataclass
class F32Artefact:
    files: dict
    manifest: dict

    def write(self, path) -> None:
        FORMAT.write(path, self.files)

    def summary(self) -> dict:
        return {"format": FORMAT.format, "steps": self.manifest["steps"], "model": self.manifest["model"]}


@dataclass
class F32Emulation(OutputSpikes):
    def arrays(self) -> dict:
        return self.output_arrays()

    def summary(self) -> dict:
        return {"precision": "float32"}

    def lines(self) -> list:
        return ["ran in float32 (the IR reference)"]

    def warnings(self) -> list:
        return []


def _graph_of(path: Path):
    from snncc.ir.serialize import load_graph

    FORMAT.open(path)
    return load_graph(Path(path) / GRAPH)


def _run(graph, x: np.ndarray) -> np.ndarray:
    import torch

    from snncc.ir.simulate import simulate

    spikes = simulate(graph, np.asarray(x, np.float32), dtype=torch.float32, record="spikes").spikes
    return np.asarray(spikes[readout_population(graph)]).astype(np.uint8)


class F32Target:
    name = "f32"
    description = "a test target: the graph run in float32"
    output_kind = "directory"
    output_suffix = ".f32.d"
    options_type = F32Options

    def lower(self, model, options=None, *, progress=None) -> F32Artefact:
        from snncc.ir.serialize import save_graph

        opts = target_options(self, options, "lower")
        steps, rule = sample_steps(model, opts.time_steps)
        with tempfile.TemporaryDirectory() as tmp:
            save_graph(model, Path(tmp) / GRAPH)
            data = (Path(tmp) / GRAPH).read_bytes()
        manifest = {"format": FORMAT.format, "snncc_version": SNNCC_VERSION, "steps": steps, "steps_rule": rule,
                    "source": source_identity(model.metadata, opts.source), "model": model_record(model),
                    "files": {GRAPH: sha256_bytes(data)}}
        if progress is not None:
            progress(1, 1, "written")
        return F32Artefact({GRAPH: data, "manifest.json": manifest_bytes(manifest)}, manifest)

    def identify(self, path: Path):
        found = FORMAT.identify(path)
        if found is not None:
            found.model = (FORMAT.manifest(path) or {}).get("model")
        return found

    def emulate(self, bundle: Path, inputs, *, record="outputs", stream=False, gap=None, source=None,
                progress=None) -> F32Emulation:
        graph = _graph_of(bundle)
        x = check_batch(inputs, source=source, field="--input")
        out = _run(graph, x)
        if progress is not None:
            progress(int(x.shape[0]))
        return F32Emulation(out)

    def _measure(self, graph, x, labels, options, artefact, inputs_text, noise):
        with artefact_to_measure(self, graph, options, artefact) as path:
            written = _graph_of(path)
            got = _run(written, x).sum(axis=1)
        want = float_counts(graph, x)
        agreement = argmax_agreement(want, got)
        acc = None if labels is None else accuracy_pair(np.argmax(want, 1), np.argmax(got, 1), labels)
        ceiling = None if noise is None else ceiling_record(noise_ceiling(graph, x, want, noise), noise)
        return report_from("f32", inputs=inputs_text, samples=len(x), steps=x.shape[1], artefact=agreement,
                           count_correlation=count_correlation(got, want),
                           stages=[stage("float32", "the graph in float32", "other", agreement,
                                         None if acc is None else acc["artefact"])],
                           possible=("other",), accuracy=acc, ceiling=ceiling)

    def check(self, graph, inputs, labels, options=None, *, artefact=None, data=None, synthetic=False,
              progress=None):
        opts = target_options(self, options, "check")
        return self._measure(graph, np.asarray(inputs), np.asarray(labels), opts, artefact,
                             f"{len(labels)} labelled samples of {data}", None)

    def agree(self, graph, inputs, options=None, agreement=None, *, artefact=None, data=None, progress=None):
        how = agreement or capability_options(AgreementOptions)
        opts = target_options(self, options, "agree")
        if inputs is None:
            steps = sample_steps(graph, None)[0]
            width = int(next(op.width for _, op in graph.items() if type(op).__name__ == "Input"))
            inputs = random_inputs(how.samples or 64, steps, width, how.density, seed=0)
            text = f"{len(inputs)} seeded random spike trains (SYNTHETIC)"
        else:
            text = f"{len(inputs)} given samples"
        if not np.all(np.isfinite(np.asarray(inputs, np.float64))):
            raise SnnccError("inputs must be finite", field="inputs")
        return self._measure(graph, np.asarray(inputs), None, opts, artefact, text, how.noise)


target = F32Target()
