"""``snncc compare``: one model on every target, on the same inputs and the same time base, in one table.

For each target (``targets``, else every installed target that can lower and check the model), the model is
compiled exactly as ``snncc compile`` would (or the ``artefacts`` given are used as their targets' rows), the
written artefact is measured by its target's own check on the same inputs (``agree`` without labels, ``check``
with; the one agreement rule; the loss in the same causes, ``kit.checks.CAUSES``) and profiled (resources,
real time, energy ESTIMATE where a published cost model exists, NeuroBench's metrics: capability ``profile``).
The float graph is a row of its own (its NeuroBench figures; accuracy with labels), and so is its weight-noise
ceiling: the float graph against itself with every weight times 1 + noise N(0, 1) (default 1 %), the
disagreement any artefact has to expect from weights of that precision.

Inputs: ``data`` (an .npz with ``inputs`` and optionally ``labels``, as ``snncc check`` takes it), else
``samples`` seeded random spike trains of ``density`` (seed 0), as long as the time base says
(``snncc.ir.timebase``: ``--time-steps``, else the model's recording length, else the one default), the same
for every row. A target that cannot take the model gives a row with its one-line reason; the others go on.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from snncc.errors import SnnccError
from snncc.measure.agreement import ArgmaxAgreement
from snncc.measure.neurobench import NeuroBenchFigures
from snncc.targets.kit.profile import EnergyEstimate, RealTime, Resource

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.ir.graph import Graph
    from snncc.progress import Progress
    from snncc.targets.base import Target

CEILING = "float, 1 % weight noise"


@dataclass
class Row:
    """One row of the table: a target's measured artefact, the float graph, or the float graph's ceiling."""

    target: str
    kind: str                                    # "float" | "ceiling" | "artefact"
    argmax_agreement: float | None = None
    argmax: ArgmaxAgreement | None = None
    accuracy: float | None = None
    causes: dict[str, float | None] = field(default_factory=dict)
    possible: list[str] = field(default_factory=list)
    total_points: float | None = None
    resources: list[Resource] = field(default_factory=list)
    real_time: RealTime | None = None
    energy: EnergyEstimate | None = None
    neurobench: NeuroBenchFigures | None = None
    sha256: str | None = None
    artefact: str | None = None                  # the path measured (the user's), or None: compiled here
    command: str | None = None                   # what rebuilds it
    error: str | None = None                     # why the target could not take the model (one line)
    notes: list[str] = field(default_factory=list)


@dataclass
class Comparison:
    model: str
    inputs: str
    samples: int
    steps: int
    steps_rule: str
    labelled: bool
    noise: float
    rows: list[Row]
    notes: list[str] = field(default_factory=list)
    figure: str | None = None
    markdown: str | None = None

    def as_dict(self) -> dict[str, object]:
        return asdict(self)

    def render_text(self, console: Console) -> None:
        from snncc.verbs.compare_table import render_text

        render_text(self, console)


def _options_for(target: Target, given: Mapping[str, object]) -> dict[str, object]:
    """The compile options among ``given`` that ``target`` declares for ``lower`` (the others are another target's)."""
    from snncc.targets.base import declared_options

    declared = {n for n, o in declared_options(target.options_type).items() if "lower" in o.capabilities}
    return {k: v for k, v in given.items() if k in declared and v not in (None, False)}


def _command(model: str, target: Target, options: Mapping[str, object], model_options: Mapping[str, object]) -> str:
    parts = ["snncc compile", model, f"--target {target.name}"]
    for name, value in {**model_options, **options}.items():
        if value in (None, False):
            continue
        flag = "--" + name.replace("_", "-")
        parts.append(flag if value is True else f"{flag} {value}")
    suffix = getattr(target, "output_suffix", None)
    out = f"{Path(model).stem}{suffix}" if isinstance(suffix, str) and suffix else f"{Path(model).stem}_{target.name}"
    return " ".join(parts + [f"-o {out}"])


@contextlib.contextmanager
def _artefact(target: Target, graph: Graph, options: Mapping[str, object], given: Path | None) -> Iterator[Path]:
    from snncc.targets import verb_options
    from snncc.targets.kit.measured import artefact_to_measure

    split = verb_options(target, dict(options), "lower")
    with artefact_to_measure(target, graph, split.target, given) as path:
        yield path


def _row(target: Target, graph: Graph, model: Path, x: np.ndarray, labels: np.ndarray | None,
         options: Mapping[str, object], model_options: Mapping[str, object], given: Path | None, data: str | None,
         report: Callable[[str], None]) -> Row:
    from snncc.artefacts import artefact_sha256, check_source, identify_own
    from snncc.targets import AgreementOptions, capability
    from snncc.targets.base import capability_options
    from snncc.targets.kit.checks import CheckReport
    from snncc.targets.kit.profile import Profile

    name = target.name
    mine = _options_for(target, options)
    row = Row(name, "artefact", command=None if given is not None else _command(str(model), target, mine, model_options),
              artefact=None if given is None else str(given))
    try:
        report(f"{name}: compiling" if given is None else f"{name}: reading the artefact")
        with _artefact(target, graph, {**mine, "source": str(model)}, given) as path:
            identity = identify_own(target, path)
            if given is not None and identity is not None:
                note = check_source(identity, graph, model)
                row.notes += [note] if note else []
            row.sha256 = artefact_sha256(path, identity.files if identity is not None else None)[0]
            report(f"{name}: measuring agreement")
            if labels is not None:
                record = capability(target, "check")(graph, x, labels, {}, artefact=path, data=data)
            else:
                record = capability(target, "agree")(graph, x, {}, capability_options(AgreementOptions, {"noise": 0.0}),
                                                     artefact=path, data=data)
            if not isinstance(record, CheckReport):
                raise SnnccError(f"target '{name}' returns no kit.checks.CheckReport from its check: it cannot be "
                                 "compared", field="--targets")
            row.argmax_agreement, row.argmax = record.argmax_agreement, ArgmaxAgreement(**record.argmax)
            row.causes, row.possible = dict(record.causes), list(record.possible)
            row.total_points = record.total_points
            row.accuracy = None if record.accuracy is None else record.accuracy.get("artefact")
            row.notes += list(record.notes)[:2]
            if callable(getattr(target, "profile", None)):
                report(f"{name}: profiling")
                profile = capability(target, "profile")(graph, path, x)
                if not isinstance(profile, Profile):
                    raise SnnccError(f"target '{name}' returns no kit.profile.Profile from its profile", field="--targets")
                row.resources, row.neurobench = list(profile.resources), profile.neurobench
                row.real_time, row.energy = profile.real_time, profile.energy
                row.notes += list(profile.notes)
            else:
                row.notes.append(f"target {name} has no profile capability: no resources, real time or NeuroBench "
                                 "figures")
    except SnnccError as err:
        row.error = err.line()
    return row


def _inputs(graph: Graph, data: Path | None, limit: int | None, samples: int | None, density: float,
            time_steps: int | None) -> tuple[np.ndarray, np.ndarray | None, str, int, str]:
    """(inputs in the graph's layout, labels or None, what they are, steps, the time base's rule)."""
    from snncc.data.check_set import load_check_data
    from snncc.ir.nodes import LIF, Input
    from snncc.ir.timebase import sample_steps
    from snncc.measure.agreement import default_samples, default_samples_note, random_inputs

    steps, rule = sample_steps(graph, time_steps)
    if data is not None:
        if samples is not None:
            raise SnnccError("applies only to random inputs, not with --data (use --limit)", field="--samples")
        try:
            x, labels, meta = load_check_data(data, graph, limit)
        except SnnccError as labelled:
            try:
                x, labels, meta = load_check_data(data, graph, limit, labels=False)
            except SnnccError:
                raise labelled from None
        synthetic = " (SYNTHETIC)" if isinstance(meta, dict) and meta.get("synthetic") else ""
        what = f"{len(x)} samples of {data}{synthetic}" + (" with labels" if labels is not None else " (no labels)")
        return np.asarray(x), None if labels is None else np.asarray(labels), what, int(np.shape(x)[1]), "the data's"
    width = int(getattr(graph.node(graph.of_kind(Input)[0]), "width"))
    neurons = int(sum(int(getattr(graph.node(p), "n")) for p in graph.of_kind(LIF)))
    n = samples if samples is not None else (limit if limit is not None else default_samples(neurons, steps))
    x = random_inputs(int(n), steps, width, density, seed=0)
    note = default_samples_note(int(n)) if samples is None and limit is None else f"{n} samples"
    return x, None, (f"{note}: seeded random spike trains (density {density:g} per channel and step, seed 0), "
                     f"{steps} steps (SYNTHETIC)"), steps, rule


def compare_model(model: str | Path, *, targets: str | Sequence[str] | None = None,
                  artefacts: Sequence[str | Path] = (), data: str | Path | None = None, limit: int | None = None,
                  samples: int | None = None, density: float = 0.08, noise: float = 0.01,
                  params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
                  output: str | Path | None = None, figure: str | Path | None = None,
                  progress: Progress | None = None, **options: object) -> Comparison:
    """The comparison of ``model`` across ``targets`` (a list or "a,b,c"; None: every installed target that lowers
    and checks), ``artefacts`` (written artefacts used as their targets' rows), on ``data`` or seeded random
    spikes (``samples``, ``density``), with the ceiling under ``noise``; ``options``: compile's target options
    (each applied to the targets that declare it). ``output`` writes the tables as Markdown, ``figure`` a PNG."""
    from snncc.artefacts import identify
    from snncc.frontends import LoadOptions, load_model
    from snncc.measure.agreement import argmax_agreement
    from snncc.measure.neurobench import float_figures
    from snncc.targets import get_target, loaded_targets, offered_options
    from snncc.targets.kit.reference import float_scores, is_spiking, noise_ceiling

    model = Path(model)
    if not 0.0 < density <= 1.0:
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    if not noise >= 0:
        raise SnnccError(f"weight noise must be >= 0, got {noise}", field="--noise")
    for name, value in (("--samples", samples), ("--limit", limit)):
        if value is not None and value < 1:
            raise SnnccError("must be a whole number >= 1", field=name)
    if output is not None and Path(output).suffix.lower() != ".md":
        raise SnnccError("the tables are written as Markdown: name the file .md", file=str(output), field="--output")
    if figure is not None and Path(figure).suffix.lower() != ".png":
        raise SnnccError("the figure is drawn as a PNG: name the file .png", file=str(figure), field="--figure")
    known = {o.name for o in offered_options(["lower"])}
    unknown = sorted(k for k, v in options.items() if v not in (None, False) and k not in known)
    if unknown:
        raise TypeError(f"no installed target takes an option {unknown[0]!r} for compile")
    given_paths: dict[str, Path] = {}
    for path in artefacts:
        tgt, _ = identify(path)
        if tgt.name in given_paths:
            raise SnnccError(f"a second {tgt.name} artefact: compare takes one per target", file=str(path),
                             field="--artefact")
        given_paths[tgt.name] = Path(path)
    if isinstance(targets, str):
        names = [t.strip() for t in targets.split(",") if t.strip()]
    elif targets is not None:
        names = list(targets)
    else:
        names = sorted({t.name for t in loaded_targets() if callable(getattr(t, "lower", None))
                        and callable(getattr(t, "agree", None))} | set(given_paths))
    for name in given_paths:
        if name not in names:
            names.append(name)
    chosen = [get_target(n) for n in names]
    model_options = {"params": params, "dt": dt, "reset": reset}
    graph = load_model(model, LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    time_steps = options.get("time_steps")
    x, labels, what, steps, rule = _inputs(graph, None if data is None else Path(data), limit, samples, density,
                                           time_steps if isinstance(time_steps, int) else None)
    total = 2 + 3 * len(chosen)
    done = [0]

    def report(phase: str) -> None:
        done[0] += 1
        if progress is not None:
            progress(min(done[0], total), total, phase)

    report("the float graph")
    spiking = is_spiking(graph)
    counts = float_scores(graph, x)
    ceiling = noise_ceiling(graph, x, counts, noise) if noise > 0 else None
    itself = argmax_agreement(counts, counts, spiking=spiking)
    float_row = Row("float", "float", argmax_agreement=1.0 if itself.defined else None, argmax=itself,
                    accuracy=None if labels is None else float(np.mean(np.argmax(counts, 1) == labels)),
                    neurobench=float_figures(graph, x) if spiking else None,
                    notes=["the reference every row is measured against"]
                    + ([] if spiking else ["not a spiking model: NeuroBench's spiking metrics are not computed"]))
    rows = [float_row]
    if ceiling is not None:
        rows.append(Row(CEILING.replace("1 %", f"{100 * noise:g} %"), "ceiling", argmax_agreement=ceiling.share,
                        argmax=ceiling, notes=["the float graph against itself, every weight times "
                                               f"1 + {noise:g} N(0, 1) (seed 9)"]))
    report("the weight-noise ceiling")
    for tgt in chosen:
        rows.append(_row(tgt, graph, model, x, labels, options, model_options, given_paths.get(tgt.name),
                         None if data is None else str(data), report))
    notes = []
    used = sorted({k for k, v in options.items() if v not in (None, False)})
    for key in used:
        takers = [t.name for t in chosen if key in _options_for(t, {key: options[key]})]
        notes.append(f"--{key.replace('_', '-')} applied to {', '.join(takers) or 'no chosen target'}")
    result = Comparison(str(model), what, int(len(x)), int(steps), rule, labels is not None, float(noise), rows, notes)
    if output is not None:
        from snncc.atomic import write_text_atomic
        from snncc.verbs.compare_table import markdown

        write_text_atomic(output, markdown(result))
        result.markdown = str(output)
    if figure is not None:
        from snncc.verbs.compare_table import draw

        draw(result, Path(figure))
        result.figure = str(figure)
    return result
