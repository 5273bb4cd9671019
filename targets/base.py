"""The target interface: what a target may offer, as typed capabilities, and its typed options.

A target is one object registered under the entry-point group ``snncc.targets``. It states
``name``, ``description``, ``output_kind`` ("file" | "directory"), optionally ``output_suffix`` (the
file suffix that names its artefact, so ``compile -o x.net`` needs no ``--target``) and ``options_type``
(a frozen dataclass derived from ``TargetOptions``), and offers any of these capabilities, each a method:

    lower(graph, options, *, progress)                       -> Artefact     (snncc compile)
    check(graph, inputs, labels, options, *, data, synthetic, progress) -> Record (snncc check)
    agree(graph, inputs, options, *, data, samples, density, noise)     -> Record (check --agreement)
    emulate(bundle, inputs, *, record, stream, gap, progress)  -> emulation  (snncc emulate, Loihi)
    run(artefact, inputs, *, source, stream, backend)          -> Record     (snncc run, Jetson)
    map(source, options)                                       -> core map   (snncc map)
    estimate(source, inputs, *, note, progress)                -> Record     (snncc report --energy)
    bench(artefacts, *, data, samples, ..., progress)          -> Record     (snncc bench)

``progress`` is ``progress(n)`` (n more samples done), except for ``bench``: ``progress(done,
total, phase)``, as the verbs report (the protocol has phases: warm-up, timing).

A third party implements only the capabilities it has; ``capability(target, "check")`` returns
the bound method or refuses in one line. Options are settings only (what the user chose); runtime
state such as a ``progress(n)`` callback is a separate keyword argument, never an option.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from snncc.errors import SnnccError

if TYPE_CHECKING:
    import numpy as np

    from snncc.ir.graph import Graph

Progress = Callable[[int], None]

# user-facing target options (option field -> command-line flag); a flagged field that a target's
# option record lacks is refused when given (not None, not False)
OPTION_FLAGS = {
    "timing": "--timing",
    "scale": "--scale",
    "allow_reset_change": "--allow-reset-change",
    "stream": "--stream",
    "jetpack": "--jetpack",
    "time_steps": "--time-steps",
}


# -- option records ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class TargetOptions:
    """Settings every target receives: ``source``, the model file's path (recorded in the artefact)."""

    source: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class IROptions(TargetOptions):
    """The ``ir`` target takes no options."""


@dataclass(frozen=True)
class LoihiOptions(TargetOptions):
    """timing: "exact" (default) | "paper"; scale: "auto" (default) | "global" | "per-layer" | "split" |
    "fine"; allow_reset_change: deploy a subtract reset as reset to zero; stream: the paper's one-stream
    protocol (check); time_steps: tSample when the model states no recording length."""

    timing: str | None = None
    scale: str | None = None
    allow_reset_change: bool = False
    stream: bool = False
    time_steps: int | None = None


@dataclass(frozen=True)
class JetsonOptions(TargetOptions):
    """jetpack: the board's JetPack ("4.6" default -> ONNX opset 13); time_steps: T of the unrolled
    sequence model (default recording_length_s / dt); seed: of the validation inputs."""

    jetpack: str | None = None
    time_steps: int | None = None
    seed: int = 0


def target_options(target: Any, given: Mapping[str, Any] | TargetOptions | None = None) -> TargetOptions:
    """``target.options_type`` built from the user-given values (None entries dropped).

    A flagged option (``OPTION_FLAGS``) given for a target whose record lacks it is refused with
    ``--flag: does not apply to --target NAME (it takes --a, --b)``; any other unknown key is a bug."""
    kind = getattr(target, "options_type", TargetOptions)
    if isinstance(given, kind):
        return given
    if isinstance(given, TargetOptions):
        given = given.as_dict()
    fields = [f.name for f in dataclasses.fields(kind)]
    values = {}
    for key, value in (given or {}).items():
        if key in fields:
            if value is not None:
                values[key] = value
        elif key in OPTION_FLAGS:
            if value is not None and value is not False:
                takes = ", ".join(OPTION_FLAGS[k] for k in fields if k in OPTION_FLAGS) or "no target options"
                raise SnnccError(f"does not apply to --target {target.name} (it takes {takes})",
                                 field=OPTION_FLAGS[key])
        else:
            raise TypeError(f"{kind.__name__} has no option {key!r}")
    return kind(**values)


# -- records and artefacts --------------------------------------------------------------------------
@runtime_checkable
class RendersText(Protocol):
    def render_text(self, console) -> None:
        """Print the record for people (rich console)."""


@runtime_checkable
class Record(RendersText, Protocol):
    """What a verb returns: ``as_dict()`` is what ``--json`` prints, ``render_text`` what the CLI prints."""

    def as_dict(self) -> dict[str, Any]: ...


class Artefact(Protocol):
    """A lowered model: something that can be written and summarised (and may render itself)."""

    def write(self, path: str | Path) -> None:
        """Write atomically (no partial output on failure), byte-identical for identical input."""

    def summary(self) -> dict[str, Any]:
        """Plain-data record of what was built (printed as text or JSON)."""


# -- capabilities -----------------------------------------------------------------------------------
class Lowers(Protocol):
    def lower(self, graph: Graph, options: TargetOptions | Mapping[str, Any] | None = None, *,
              progress: Progress | None = None) -> Artefact:
        """Lower a validated IR graph; raise SnnccError if the target cannot express it."""


class Checks(Protocol):
    def check(self, graph: Graph, inputs: np.ndarray, labels: np.ndarray,
              options: TargetOptions | Mapping[str, Any] | None = None, *, data: str | None = None,
              synthetic: bool = False, progress: Progress | None = None) -> Record:
        """What deploying costs on a labelled data set (N, T, C); ``progress(n)`` after n samples."""


class Agrees(Protocol):
    def agree(self, graph: Graph, inputs: np.ndarray | None, options: TargetOptions | Mapping[str, Any] | None = None,
              *, data: str | None = None, samples: int = 40, density: float = 0.08, noise: float = 0.01) -> Record:
        """Agreement with the float graph without labels (None inputs: seeded random spikes)."""


class Emulates(Protocol):
    def emulate(self, bundle: Path, inputs: np.ndarray, *, record: str = "outputs", stream: bool = False,
                gap: int | None = None, source: str | None = None, progress: Progress | None = None) -> Any:
        """Run a written artefact in the target's emulator; the result offers ``arrays()`` to save."""


class Runs(Protocol):
    def run(self, artefact: Path, inputs: np.ndarray, *, source: str | None = None, stream: bool = False,
            backend: str = "auto") -> Any:
        """Run a written artefact on inputs; the result holds the output arrays."""


class Maps(Protocol):
    def map(self, source: Path, options: TargetOptions | Mapping[str, Any] | None = None) -> Any:
        """Place an artefact (or a model, lowered first) on the hardware; the map renders itself."""


class Estimates(Protocol):
    def estimate(self, source: Path, inputs: Any, *, data: str | None = None, note: str = "", limit: int | None = None,
                 progress: Progress | None = None) -> Record:
        """ESTIMATE of energy and delay per sample of an artefact on inputs."""


class Benches(Protocol):
    def bench(self, artefacts: list[Path], **protocol: Any) -> Record:
        """Measured latency (and power) of written artefacts."""


CAPABILITIES: dict[str, type] = {
    "lower": Lowers, "check": Checks, "agree": Agrees, "emulate": Emulates, "run": Runs, "map": Maps,
    "estimate": Estimates, "bench": Benches,
}


class Target(Protocol):
    name: str
    description: str
    output_kind: str  # "file" or "directory"
    options_type: type[TargetOptions]
    # optional ``output_suffix``: the file suffix that names this target's artefact (".net"), so that
    # ``compile -o x.net`` needs no --target; a target without one (a directory) is always named


def capability(target: Any, name: str, rule: str | None = None) -> Callable[..., Any]:
    """``target``'s bound capability ``name`` (one of ``CAPABILITIES``), or a one-line refusal.

    ``rule`` replaces the default refusal text (``target 'X' has no NAME in this snncc``)."""
    if name not in CAPABILITIES:
        raise ValueError(f"unknown capability {name!r} (known: {', '.join(CAPABILITIES)})")
    method = getattr(target, name, None)
    if not callable(method):
        raise SnnccError(rule or f"target {target.name!r} has no {name} in this snncc", field="--target")
    return method
