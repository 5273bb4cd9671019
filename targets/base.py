"""The target interface: a target's typed options and the capabilities it may offer (``docs/targets.md``).

A target is one object registered under the entry-point group ``snncc.targets``; the module the
entry point names must import nothing heavy (no torch, onnx, onnxruntime or numba: each capability
imports its work when called), so listing or choosing a target is instant. The object states
``name``, ``description``, ``output_kind`` ("file" | "directory") and ``options_type`` (a frozen
dataclass derived from ``TargetOptions``); optionally ``output_suffix`` (the file suffix that names
its artefact, so ``compile -o x.net`` needs no ``--target``) and ``model_kinds`` (default
``("graph",)``: which model records its ``lower`` takes; "buffered": a buffered classifier without
an IR graph).

**Options.** A target declares its options as fields of its record made with ``option(help, ...)``:
the field's name is the keyword (``time_steps``), its flag the name with dashes (``--time-steps``),
its type (bool: a switch; int, float or str: a value; ``None`` default: not given) and the
declaration's choices, bounds and ``capabilities`` (the capabilities whose verbs offer it: "lower"
is ``snncc compile``, "check" and "agree" ``snncc check``, "map" ``snncc map``) are all the CLI and
the verbs need: ``snncc.cli`` builds each command's flags from the registered targets'
declarations and the verbs pass options through without naming them. The rules:

* the chosen target validates: ``target_options(target, given, capability)`` builds its record,
  refusing a value outside the declaration (``--scale: scale must be one of ...``) and an option it
  does not take, in one line: ``--flag: does not apply to --target NAME (it takes --a, --b)``;
* two targets may declare the same flag: the command offers it once, its help naming the targets
  that take it (``--target jetson, loihi``); each target validates its own declaration (a flag that
  is a switch for one target and a value for another is refused when the flags are built);
* options that belong to a capability rather than a target are declared once, here, in that
  capability's record (``CAPABILITY_OPTIONS``: ``AgreementOptions`` of ``agree``, ``FinetuneOptions``
  of ``finetune``) and offered by every target that has the capability; the capability receives the
  record;
* an option naming a file says so (``path="input"``: read, so no output may overwrite it;
  ``path="output"``: written), and the CLI protects it like the command's own path parameters.

Options are settings only (what the user chose); runtime state such as a progress callback is a
separate keyword argument, never an option.

**Capabilities**, each a method (``capability(target, name)`` returns it or refuses in one line):

    lower(model, options, *, progress)                       -> Artefact        snncc compile
    identify(path)                                           -> ArtefactIdentity | None  is it ours?
    check(graph, inputs, labels, options, *, artefact, data, synthetic, progress) -> Record  snncc check --data
    agree(graph, inputs, options, agreement, *, artefact, data, progress) -> Record  snncc check (no labels)
    emulate(bundle, inputs, *, record, stream, gap, source, progress) -> Emulation  snncc emulate
    run(artefact, inputs, *, source, stream, backend)        -> RunResult       snncc run
    map(source, options)                                     -> CoreMap         snncc map
    estimate(source, inputs, *, data, note, limit, progress) -> Record          snncc report --energy
    profile(graph, artefact, inputs, *, progress)            -> Profile         snncc compare (resources, real
                                                                                time, energy, NeuroBench)
    bench(artefacts, *, data, samples, ..., progress)        -> Record          snncc bench
    hardware()                                               -> HardwareCosts   snncc hpo (per trial)
    arithmetic(options)                                      -> Arithmetic      snncc train --qat-from
    finetune(model, inputs, options, finetuning, *, labels, data, progress) -> FinetunedArtefact
                                                                                snncc compile --finetune

``check`` and ``agree`` measure the written artefact at ``artefact`` (run again, never echoed from what
compile recorded; None: the artefact compile would write, in a temporary directory); ``identify``
recognises the target's own artefacts (``snncc.artefacts``: ``check --artefact``, compile's hash).
``progress`` is ``progress(n)`` (n more samples done) for the sample loops of check, agree, emulate and
estimate; ``progress(done, total, phase)`` (``snncc.progress.Progress``) for lower and bench, whose
work has phases (lower: measuring scale candidates, validating; bench: warm-up, timing).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Literal, Protocol, TypeVar, Union, get_args, overload, runtime_checkable

from snncc.errors import SnnccError
from snncc.progress import Progress as PhaseProgress

if TYPE_CHECKING:
    import numpy as np
    import torch
    from rich.console import Console

    from snncc.artefacts import ArtefactIdentity
    from snncc.frontends.buffered import BufferedModel
    from snncc.ir.liveness import SpikeActivity
    from snncc.ir.graph import Graph

    Model = Union[Graph, BufferedModel]   # what ``lower`` receives (a record of ``model_kinds``)

Progress = Callable[[int], None]
OptionValue = Union[bool, int, float, str, None]
OPTION_KEY = "snncc.option"
VERB_OF = {"lower": "compile", "check": "check with labelled data", "agree": "check without labels (agreement)",
           "map": "map", "finetune": "fine-tuning"}
PATH_ROLES = ("", "input", "output")   # an option naming a file the command reads, or one it writes


# -- option declarations ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Option:
    """One declared option: ``help`` (what it does, for ``--help``), its ``kind`` (bool | int | float |
    str, read from the field's type), ``choices`` (str values allowed), bounds (``minimum``,
    ``maximum`` inclusive; ``above``: strictly greater), ``rule`` (the refusal's text when a value
    breaks them), ``capabilities`` (whose verbs offer it) and ``path`` ("input": a file the command
    reads, protected from every output; "output": a file it writes; "": not a path). ``name``/``default``
    come from the field."""

    help: str
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    maximum: float | None = None
    above: float | None = None
    rule: str = ""
    capabilities: tuple[str, ...] = ("lower", "check", "agree")
    path: str = ""
    name: str = ""
    kind: type = str
    default: OptionValue = None

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    @property
    def switch(self) -> bool:
        return self.kind is bool

    def _refuse(self, value: object) -> SnnccError:
        if self.rule:
            text = self.rule if self.choices else f"{self.rule}, got {value}"
        elif self.choices:
            text = f"must be one of {', '.join(self.choices)}, got {value!r}"
        else:
            bounds = [f">= {self.minimum:g}"] if self.minimum is not None else []
            bounds += [f"> {self.above:g}"] if self.above is not None else []
            bounds += [f"<= {self.maximum:g}"] if self.maximum is not None else []
            what = {bool: "true or false", int: "a whole number", float: "a number"}.get(self.kind, "text")
            text = f"must be {what}{' ' + ' and '.join(bounds) if bounds else ''}, got {value!r}"
        return SnnccError(text, field=self.flag)

    def parse(self, value: object) -> OptionValue:
        """``value`` (a Python value, or the CLI's text where targets disagree on the type) as this
        option's kind, within its choices and bounds; else a one-line refusal."""
        if self.kind is bool:
            if not isinstance(value, bool):
                raise self._refuse(value)
            return value
        if self.kind in (int, float):
            number = _number(value)
            if number is None or not math.isfinite(number) or (self.kind is int and number != int(number)):
                raise self._refuse(value)
            if ((self.minimum is not None and number < self.minimum) or (self.above is not None and number <= self.above)
                    or (self.maximum is not None and number > self.maximum)):
                raise self._refuse(value)
            return int(number) if self.kind is int else number
        if not isinstance(value, str) or (self.choices and value not in self.choices):
            raise self._refuse(value)
        return value


def _number(value: object) -> float | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        try:
            return float(int(value)) if value.strip().lstrip("+-").isdigit() else float(value)
        except ValueError:
            return None
    return None


T = TypeVar("T", bool, int, float, str)


@overload
def option(help: str, *, default: None = None, choices: Sequence[str] = (), minimum: float | None = None,
           maximum: float | None = None, above: float | None = None, rule: str = "",
           capabilities: Sequence[str] = ("lower", "check", "agree"), path: str = "") -> None: ...
@overload
def option(help: str, *, default: T, choices: Sequence[str] = (), minimum: float | None = None,
           maximum: float | None = None, above: float | None = None, rule: str = "",
           capabilities: Sequence[str] = ("lower", "check", "agree"), path: str = "") -> T: ...


def option(help: str, *, default: OptionValue = None, choices: Sequence[str] = (), minimum: float | None = None,
           maximum: float | None = None, above: float | None = None, rule: str = "",
           capabilities: Sequence[str] = ("lower", "check", "agree"), path: str = "") -> OptionValue:
    """A dataclass field declaring a user-facing option (see the module doc); use as a field's default:

        time_steps: int | None = option("T of the unrolled model.", minimum=1, capabilities=("lower",))
    """
    if path not in PATH_ROLES:
        raise ValueError(f"an option's path role is one of {PATH_ROLES}, not {path!r}")
    declared = Option(help=help, choices=tuple(choices), minimum=minimum, maximum=maximum, above=above, rule=rule,
                      capabilities=tuple(capabilities), path=path)
    field: OptionValue = dataclasses.field(default=default, metadata={OPTION_KEY: declared})
    return field


_KINDS = {"bool": bool, "int": int, "float": float, "str": str}


def _kind(annotation: object) -> type:
    """bool, int, float or str from a field's annotation (``int | None``, ``Optional[str]``, ``bool``;
    a string under ``from __future__ import annotations``)."""
    if isinstance(annotation, str):
        text = annotation.replace("typing.", "").replace("Optional[", "").replace("]", "")
        parts = {p.strip() for p in text.split("|")}
    else:
        parts = {getattr(a, "__name__", str(a)) for a in (get_args(annotation) or (annotation,))}
    parts -= {"None", "NoneType"}
    if len(parts) != 1 or next(iter(parts)) not in _KINDS:
        raise TypeError(f"an option's type must be bool, int, float or str (or one of them | None), not {annotation!r}")
    return _KINDS[next(iter(parts))]


def declared_options(record: type[OptionRecord]) -> dict[str, Option]:
    """Field name -> its declaration, for every ``option(...)`` field of ``record``, in field order."""
    out: dict[str, Option] = {}
    for f in dataclasses.fields(record):
        spec = f.metadata.get(OPTION_KEY)
        if isinstance(spec, Option):
            default = f.default if isinstance(f.default, (bool, int, float, str)) else None
            out[f.name] = dataclasses.replace(spec, name=f.name, kind=_kind(f.type), default=default)
    return out


# -- option records ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class OptionRecord:
    """A frozen record of settings (a target's options, or a capability's)."""

    def as_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class TargetOptions(OptionRecord):
    """Settings every target receives: ``source``, the model file's path (recorded in the artefact)."""

    source: str | None = None


@dataclass(frozen=True)
class AgreementOptions(OptionRecord):
    """The label-free agreement's settings (capability ``agree``): seeded random inputs and the ceiling."""

    samples: int | None = option(
        "Without data: seeded random input samples of the agreement, as long as the artefact's own sample "
        "(default 1,000: a 95 % interval of about +-0.03; 200 for a model of more than 200,000 neuron-steps per "
        "sample).", minimum=1, rule="must be a whole number >= 1", capabilities=("agree",))
    density: float = option("Without data: spike density of the seeded random inputs.", default=0.08, above=0,
                            maximum=1, rule="spike density must be in (0, 1]", capabilities=("agree",))
    noise: float = option("Multiplicative weight noise for the float graph's own sensitivity (the ceiling).",
                          default=0.01, minimum=0, rule="weight noise must be >= 0", capabilities=("agree",))


DEVICE_RULE = "must be auto, cpu, cuda or cuda:N"


@dataclass(frozen=True)
class FinetuneOptions(OptionRecord):
    """Deployment fine-tuning's settings (capability ``finetune``, ``docs/finetune.md``): the lowered model
    trained through the target's integer arithmetic towards the float graph as trained (no labels)."""

    finetune: bool = option("Fine-tune the lowered model to the chip's arithmetic, the float graph as trained being "
                            "the teacher (no labels; docs/finetune.md).", default=False, capabilities=("finetune",))
    finetune_out: str | None = option("With --finetune: also write the adapted float graph (the fine-tuned "
                                      "parameters in float units) as NIR to this file.", capabilities=("finetune",),
                                      path="output")
    data: str | None = option("With --finetune: the inputs to fine-tune on (the files snncc check takes; labels, "
                              "where present, only measure task accuracy on the held-out part).",
                              capabilities=("finetune",), path="input")
    density: float | None = option("With --finetune, without --data: spike density of the seeded random inputs "
                                   "(default 0.08).", above=0, maximum=1, rule="spike density must be in (0, 1]",
                                   capabilities=("finetune",))
    device: str | None = option("With --finetune: where it trains: auto (CUDA when present), cpu (default), cuda "
                                "or cuda:N.", capabilities=("finetune",))
    finetune_samples: int = option("With --finetune, without --data: seeded random training samples; validation (which "
                                   "chooses the kept epoch) and held-out samples (which measure it) scale with them: "
                                   "500 and 1,000 for 2,048, at least 128 and 256.", default=2048,
                                   minimum=1, rule="must be a whole number >= 1", capabilities=("finetune",))
    finetune_epochs: int = option("With --finetune: training epochs.", default=6, minimum=1,
                                  rule="must be a whole number >= 1", capabilities=("finetune",))
    finetune_seed: int = option("With --finetune: the seed of its inputs, split and training.", default=0, minimum=0,
                                rule="must be a whole number >= 0", capabilities=("finetune",))


CAPABILITY_OPTIONS: dict[str, type[OptionRecord]] = {"agree": AgreementOptions, "finetune": FinetuneOptions}

R = TypeVar("R", bound=OptionRecord)
Given = Union[Mapping[str, object], OptionRecord, None]


def _uses(capability: str | Sequence[str] | None) -> tuple[str, ...]:
    return () if capability is None else (capability,) if isinstance(capability, str) else tuple(capability)


def _takes(target: Target, capability: str | Sequence[str] | None) -> str:
    uses = set(_uses(capability))
    flags = [o.flag for o in declared_options(target.options_type).values() if not uses or uses & set(o.capabilities)]
    return ", ".join(flags) or "no target options"


def _values(kind: type[OptionRecord], given: Given) -> dict[str, object]:
    if isinstance(given, OptionRecord):
        return given.as_dict()
    return {k: v for k, v in (given or {}).items()}


def target_options(target: Target, given: Given = None, capability: str | Sequence[str] | None = None
                   ) -> TargetOptions:
    """``target.options_type`` built from the user-given values (None entries dropped), each value
    validated by the target's declaration. A given option (not None, not False) that the record lacks
    is refused: ``--flag: does not apply to --target NAME (it takes --a, --b)``; one the target takes
    only for other verbs than ``capability``'s (one capability, or the several a verb calls):
    ``--flag: does not apply to <verb> (--target NAME takes it for <verbs>)``."""
    uses = _uses(capability)
    kind = getattr(target, "options_type", TargetOptions)
    if isinstance(given, kind):
        return given
    steps = _values(kind, given).get("time_steps")
    if isinstance(steps, (int, float)) and not isinstance(steps, bool) and steps > 1:
        from snncc.limits import check_time_steps

        check_time_steps(float(steps), "this value", field="--time-steps")   # the cap every sample obeys
    declared = declared_options(kind)
    fields = {f.name for f in dataclasses.fields(kind)}
    values: dict[str, object] = {}
    for key, value in _values(kind, given).items():
        if value is None:
            continue
        if key not in fields:
            if value is not False:
                raise SnnccError(f"does not apply to --target {target.name} (it takes {_takes(target, capability)})",
                                 field="--" + key.replace("_", "-"))
            continue
        spec = declared.get(key)
        if spec is None:
            values[key] = value
            continue
        if uses and not set(uses) & set(spec.capabilities):
            if value is False:
                continue
            verbs = ", ".join(dict.fromkeys(VERB_OF.get(c, c) for c in spec.capabilities))
            raise SnnccError(f"does not apply to {VERB_OF.get(uses[0], uses[0])} (--target {target.name} takes it "
                             f"for {verbs})", field=spec.flag)
        values[key] = spec.parse(value)
    build: Callable[..., TargetOptions] = kind
    return build(**values)


def capability_options(kind: type[R], given: Given = None) -> R:
    """A capability's option record (``AgreementOptions``) from the given values (None dropped), each
    validated by its declaration; a key the record lacks is a bug (TypeError)."""
    if isinstance(given, kind):
        return given
    declared = declared_options(kind)
    values: dict[str, object] = {}
    for key, value in _values(kind, given).items():
        if key not in declared:
            raise TypeError(f"{kind.__name__} has no option {key!r}")
        if value is not None:
            values[key] = declared[key].parse(value)
    build: Callable[..., R] = kind
    return build(**values)


# -- records and artefacts --------------------------------------------------------------------------
@runtime_checkable
class RendersText(Protocol):
    def render_text(self, console: Console) -> None:
        """Print the record for people (rich console)."""


@runtime_checkable
class Record(RendersText, Protocol):
    """What a verb returns: ``as_dict()`` is what ``--json`` prints, ``render_text`` what the CLI prints."""

    def as_dict(self) -> Mapping[str, object]: ...


class Artefact(Protocol):
    """A lowered model: something that can be written and summarised (and may render itself)."""

    def write(self, path: str | Path) -> None:
        """Write atomically (no partial output on failure), byte-identical for identical input."""

    def summary(self) -> Mapping[str, object]:
        """Plain-data record of what was built (printed as text or JSON)."""


@runtime_checkable
class KnowsFloatActivity(Protocol):
    """Optional on an ``Artefact``: the float model's activity on compile's calibration inputs, where lowering
    already ran the float model on them (``snncc.ir.liveness.calibration_spikes`` at ``steps`` steps), so that
    compile's silence warning does not run it again. ``float_calibration_activity(steps)``: population name ->
    ``snncc.ir.liveness.SpikeActivity`` of the model as given, or None where it was not run on those inputs."""

    def float_calibration_activity(self, steps: int) -> Mapping[str, SpikeActivity] | None: ...


class HasArrays(Protocol):
    def arrays(self) -> Mapping[str, np.ndarray]:
        """The output arrays to save (.npz)."""


class Emulation(HasArrays, Protocol):
    """What ``emulate`` returns (and what ``snncc emulate`` writes to its .npz).

    ``arrays()`` holds at least ``output_spikes`` (B, T, N) uint8 (the model's T steps, whatever the target
    shifted or padded), ``counts`` (B, N) int64 and ``prediction`` (B,) int64 (argmax of the counts, ties to
    the lowest index); with ``record="all"`` also the target's recorded states, each named
    ``<population or layer>_<what>`` (``layer1_voltage``), as documented by the target. ``samples``, ``steps``
    (T) and ``prediction`` are read by the verb; ``summary()`` (plain data: overflow counts, padding, the
    input layout taken) and ``lines()`` (what the verb prints about the run besides its size) are the
    target's own, and ``warnings()`` what the user should know but is not the result."""

    @property
    def samples(self) -> int: ...

    @property
    def steps(self) -> int: ...

    @property
    def prediction(self) -> np.ndarray: ...

    def summary(self) -> Mapping[str, object]: ...

    def lines(self) -> Sequence[str]: ...

    def warnings(self) -> Sequence[str]: ...


class RunResult(HasArrays, Protocol):
    def as_dict(self) -> Mapping[str, object]: ...


class CoreMap(RendersText, Protocol):
    def to_dict(self) -> Mapping[str, object]: ...

    def plot(self, path: str | Path) -> object: ...


# -- capabilities: each the signature of the target's method of that name -------------------------
class Lower(Protocol):
    def __call__(self, model: Model, options: Given = None, *, progress: PhaseProgress | None = None) -> Artefact:
        """Lower a validated IR graph (or a record of ``model_kinds``); raise SnnccError if the target cannot
        express it. ``progress(done, total, phase)`` as the work goes."""


class Identify(Protocol):
    def __call__(self, path: Path) -> ArtefactIdentity | None:
        """``snncc.artefacts.ArtefactIdentity`` when ``path`` is this target's written artefact, else None
        (cheap: reads what the artefact records, runs nothing)."""


class Check(Protocol):
    def __call__(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
                 artefact: Path | None = None, data: str | None = None, synthetic: bool = False,
                 progress: Progress | None = None) -> Record:
        """What the written ``artefact`` (run again; None: the one compile would write) costs against
        ``graph`` on a labelled data set (N, T, C) read from ``data`` (errors name it; ``synthetic``: say
        so); ``progress(n)`` after n samples."""


class Agree(Protocol):
    def __call__(self, graph: Graph, inputs: np.ndarray | None, options: Given = None,
                 agreement: AgreementOptions | None = None, *, artefact: Path | None = None,
                 data: str | None = None, progress: Progress | None = None) -> Record:
        """The written ``artefact``'s agreement (None: the one compile would write) with the float graph
        without labels (None inputs: ``agreement.samples`` seeded random spike trains of
        ``agreement.density``, default ``snncc.measure.agreement.default_samples``; the float graph's own
        ceiling under ``agreement.noise``); ``progress(n)`` after n samples."""


@runtime_checkable
class FinetunedArtefact(Artefact, Protocol):
    """What ``finetune`` returns: the artefact (written and summarised as ``lower``'s, the summary holding a
    ``finetune`` entry: inputs, seed, steps, held-out agreement before and after with its interval)."""

    def adapted_graph(self) -> Graph:
        """The fine-tuned parameters read back as a float IR graph (what ``--finetune-out`` writes as NIR)."""

    def finetune_record(self) -> Mapping[str, object]:
        """What fine-tuning did and measured, plain data (the summary's ``finetune`` entry)."""


class Finetune(Protocol):
    def __call__(self, model: Model, inputs: np.ndarray | None, options: Given = None,
                 finetuning: FinetuneOptions | None = None, *, labels: np.ndarray | None = None,
                 data: str | None = None, progress: PhaseProgress | None = None) -> FinetunedArtefact:
        """Lower ``model`` as ``lower`` does, then train the lowered parameters through the target's integer
        arithmetic towards the float graph as trained on ``inputs`` (N, T, C) read from ``data`` (None:
        ``finetuning``'s seeded random spikes); ``labels`` only measure task accuracy on the held-out part.
        ``progress(done, total, phase)`` as it trains."""


class Emulate(Protocol):
    def __call__(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                 gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Emulation:
        """Run a written artefact in the target's emulator."""


class Run(Protocol):
    def __call__(self, artefact: Path, inputs: np.ndarray, *, source: str | None = None, stream: bool = False,
                 backend: str = "auto") -> RunResult:
        """Run a written artefact on inputs; the result holds the output arrays."""


class Map(Protocol):
    def __call__(self, source: Path, options: Given = None) -> CoreMap:
        """Place an artefact (or a model, lowered first with ``options``) on the hardware."""


class Estimate(Protocol):
    def __call__(self, source: Path, inputs: object, *, data: str | None = None, note: str = "",
                 limit: int | None = None, progress: Progress | None = None) -> Record:
        """ESTIMATE of energy and delay per sample of an artefact on inputs (an array, or
        ``snncc.inputs.RandomSpikes``)."""


class Profile(Protocol):
    def __call__(self, graph: Graph, artefact: Path, inputs: np.ndarray, *, progress: Progress | None = None) -> Record:
        """What the written ``artefact`` (compiled from ``graph``) costs on its hardware
        (``snncc.targets.kit.profile.Profile``): resources against the chip's limits, the real-time verdict and the
        energy ESTIMATE where a published cost model exists, at the event rates of ``inputs`` (B, T, C) in the
        graph's input layout; NeuroBench's metrics from its own emulation or run."""


class Bench(Protocol):
    def __call__(self, artefacts: list[Path], *, data: Path | None = None, samples: int = 64, power: bool = False,
                 power_root: Path = Path("/"), rail: str = "VDD_IN", repeats: int = 3, warmup_passes: int = 6,
                 timed_passes: int = 6, stream: bool = False, backend: str = "auto",
                 progress: PhaseProgress | None = None) -> Record:
        """Measured latency (and power) of written artefacts, the paper's protocol."""


@dataclass(frozen=True)
class Objective:
    """A figure a hardware-aware search may optimise: ``key`` in the figures' ``as_dict()``, its
    ``direction`` ("minimize" | "maximize") and ``unit`` (with ESTIMATE where it is one)."""

    key: str
    direction: str
    unit: str


@dataclass(frozen=True)
class Figure:
    """A figure a search report shows for each trial: ``key`` in the figures' ``as_dict()``; ``heading``, its
    table column (unit included, EST. where it is an ESTIMATE); ``axis``, its plot axis label (default: the
    heading); shown value = stored value x ``scale`` (a fraction shown in %: 100); ``log``: plotted on a log
    axis; ``field``: its name in the report's JSON rows (default: the column's name)."""

    key: str
    heading: str
    axis: str = ""
    scale: float = 1.0
    log: bool = False
    field: str = ""


class HardwareFigures(Protocol):
    def as_dict(self) -> Mapping[str, object]:
        """Plain data, stored with each trial; the keys of ``HardwareCosts.objectives`` among them."""


class HardwareCosts(Protocol):
    """What a model costs on the target, per search trial (capability ``hardware``).

    ``objectives``: name -> ``Objective`` (Loihi: energy, delay, synops, cores, emulated_accuracy; a
    target with another budget declares its own, e.g. neurons used or real-time margin);
    ``columns``: name -> ``Figure``, the figures a search report shows, in column order (those named
    in ``objectives`` are objectives); ``front``: the objectives the report's Pareto front weighs
    beside accuracy, the figure plotting accuracy against the first two;
    ``published``: a published measurement shown beside the trials (objective names and ``accuracy``
    in %, ``label``), or empty; ``label``: what the figures are (ESTIMATE wording)."""

    @property
    def objectives(self) -> Mapping[str, Objective]: ...

    @property
    def columns(self) -> Mapping[str, Figure]: ...

    @property
    def front(self) -> tuple[str, ...]: ...

    @property
    def published(self) -> Mapping[str, float | str]: ...

    @property
    def label(self) -> str: ...

    def figures(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: Given = None, *,
                estimate_samples: int = 16, emulate_samples: int = 0) -> HardwareFigures:
        """Lower ``graph`` and measure or ESTIMATE its cost on the first ``estimate_samples`` of
        ``inputs`` (B, T, C); ``emulate_samples`` > 0: also the deployed accuracy on that many."""


class Hardware(Protocol):
    def __call__(self) -> HardwareCosts: ...


@dataclass(frozen=True)
class NeuronConstants:
    """A LIF population's float constants, as trained: threshold, time step and time constants (s)."""

    threshold: float
    dt: float
    tau_syn: float
    tau_mem: float


class QuantizedParameters(Protocol):
    """The parameters the chip would run, in the float model's units: ``weights`` (name -> tensor,
    straight-through: forward = the chip's value, gradient = identity), ``threshold``, per-step decay
    factors ``alpha`` (current) and ``beta`` (voltage), and ``record`` (the integers chosen, plain data)."""

    @property
    def weights(self) -> Mapping[str, torch.Tensor]: ...

    @property
    def threshold(self) -> float: ...

    @property
    def alpha(self) -> float: ...

    @property
    def beta(self) -> float: ...

    @property
    def record(self) -> Mapping[str, int | float]: ...


class Arithmetic(Protocol):
    """The target's arithmetic as differentiable operations, to train through it (capability
    ``arithmetic``). Today: its quantization of weights, threshold and decays (straight-through
    rounding); a full model of its integer dynamics (state rounding, saturation, reset, spike rule)
    belongs here too, as methods beside ``quantize``."""

    @property
    def label(self) -> str:
        """The chip's name in records ("Loihi")."""

    def quantize(self, weights: Mapping[str, torch.Tensor], neurons: NeuronConstants) -> QuantizedParameters:
        """The chip's parameters for a network with ``weights`` (all its projections) and ``neurons``."""


class TrainArithmetic(Protocol):
    def __call__(self, options: Given = None) -> Arithmetic: ...


CAPABILITIES: dict[str, type] = {
    "lower": Lower, "identify": Identify, "check": Check, "agree": Agree, "emulate": Emulate, "run": Run, "map": Map,
    "estimate": Estimate, "bench": Bench, "hardware": Hardware, "arithmetic": TrainArithmetic,
    "finetune": Finetune, "profile": Profile,
}


class Target(Protocol):
    """What every target states (class attributes will do): ``output_kind`` is "file" or "directory".
    Optional: ``output_suffix``, the file suffix that names its artefact (".net"), so that ``compile -o
    x.net`` needs no --target (a target without one, e.g. a directory, is always named); ``model_kinds``;
    ``replace_refusal(path)`` (a directory target: why an existing directory may not be replaced, None where it
    may, as its writer decides: ``compile`` refuses before lowering instead of after)."""

    @property
    def name(self) -> str: ...

    @property
    def description(self) -> str: ...

    @property
    def output_kind(self) -> str: ...

    @property
    def options_type(self) -> type[TargetOptions]: ...


def model_kinds(target: Target) -> tuple[str, ...]:
    """The model records ``target.lower`` takes: ("graph",) unless the target states more."""
    kinds = getattr(target, "model_kinds", ("graph",))
    return tuple(kinds) if isinstance(kinds, (tuple, list)) else ("graph",)


@overload
def capability(target: Target, name: Literal["lower"], rule: str | None = None) -> Lower: ...
@overload
def capability(target: Target, name: Literal["check"], rule: str | None = None) -> Check: ...
@overload
def capability(target: Target, name: Literal["agree"], rule: str | None = None) -> Agree: ...
@overload
def capability(target: Target, name: Literal["emulate"], rule: str | None = None) -> Emulate: ...
@overload
def capability(target: Target, name: Literal["run"], rule: str | None = None) -> Run: ...
@overload
def capability(target: Target, name: Literal["map"], rule: str | None = None) -> Map: ...
@overload
def capability(target: Target, name: Literal["estimate"], rule: str | None = None) -> Estimate: ...
@overload
def capability(target: Target, name: Literal["bench"], rule: str | None = None) -> Bench: ...
@overload
def capability(target: Target, name: Literal["profile"], rule: str | None = None) -> Profile: ...
@overload
def capability(target: Target, name: Literal["hardware"], rule: str | None = None) -> Hardware: ...
@overload
def capability(target: Target, name: Literal["arithmetic"], rule: str | None = None) -> TrainArithmetic: ...
@overload
def capability(target: Target, name: Literal["finetune"], rule: str | None = None) -> Finetune: ...
@overload
def capability(target: Target, name: str, rule: str | None = None) -> Callable[..., object]: ...


def capability(target: Target, name: str, rule: str | None = None) -> Callable[..., object]:
    """``target``'s bound capability ``name`` (one of ``CAPABILITIES``, its signature that protocol's
    ``__call__``), or a one-line refusal. ``rule`` replaces the default refusal text (``target 'X' has
    no NAME in this snncc``)."""
    if name not in CAPABILITIES:
        raise ValueError(f"unknown capability {name!r} (known: {', '.join(CAPABILITIES)})")
    method = getattr(target, name, None)
    if not callable(method):
        raise SnnccError(rule or f"target {target.name!r} has no {name} in this snncc", field="--target")
    found: Callable[..., object] = method
    return found
