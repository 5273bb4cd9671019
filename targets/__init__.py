"""Targets, found through the ``snncc.targets`` entry-point group (third parties plug in there).

The interface is ``snncc.targets.base`` (and ``docs/targets.md``): a target names its typed option
record (``options_type``, fields declared with ``option(...)``) and offers any of the capabilities
there. The verbs (``snncc.api``) ask ``capability(get_target(name), verb)`` and refuse in one line
when the target lacks it; they pass the user's options through ``verb_options``, and the CLI builds
each command's flags from ``offered_options``: both read the registered targets' declarations, so
a target's option needs no edit in snncc.

A third-party package registers its target object in its own metadata::

    [project.entry-points."snncc.targets"]
    xylo = "snncc_xylo:target"

The module named there must be light (no torch, onnx, onnxruntime or numba at import): listing or
choosing a target loads it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from typing import TypeVar

from snncc.errors import SnnccError
from snncc.targets.base import (
    CAPABILITY_OPTIONS, VERB_OF, AgreementOptions, Artefact, FinetuneOptions, Given, Option, OptionRecord, Record,
    Target, TargetOptions, capability, capability_options, declared_options, model_kinds,
)
from snncc.targets.base import target_options as _target_options

GROUP = "snncc.targets"
DEFAULT_TARGET = "loihi"       # what compile, check and hpo use without --target (the paper's chip): the one place
R = TypeVar("R", bound=OptionRecord)

# the own parameters of the commands that offer target flags (compile, check, map, hpo run, compare; a test keeps
# this list complete): a target option of one of these names would shadow them, so such a target is refused at
# registration, alone (the capabilities' own options, declared in base, are not counted)
RESERVED_OPTIONS = frozenset({
    "agreement", "artefact", "batch_size", "data", "device", "dt", "emulate", "energy_samples", "epochs", "figure",
    "grid_span", "heartbeat", "hidden", "json_out", "limit", "model", "name", "objectives", "output", "params", "plot",
    "preset", "pruner", "quiet", "ranges", "reset", "restarts", "seed", "select", "source", "startup", "step",
    "storage", "subset", "target", "targets", "threads", "threshold", "trials", "val_fraction", "workdir",
})


def available_targets() -> list[str]:
    return sorted({ep.name for ep in entry_points(group=GROUP)})


def output_suffixes() -> dict[str, str]:
    """Target name -> the file suffix that names its artefact (``output_suffix``), for the installed targets
    that declare one. A target that fails to load is passed over: it cannot be chosen without being named."""
    found = {}
    for target in loaded_targets():   # a broken third-party plug-in: named with --target, it reports itself
        declared = getattr(target, "output_suffix", None)
        if isinstance(declared, str) and declared:
            found[target.name] = declared
    return dict(sorted(found.items()))


def targets_for_suffix(suffix: str) -> list[str]:
    """The installed targets whose artefact's suffix is ``suffix`` (case-blind)."""
    return [name for name, declared in output_suffixes().items() if declared.lower() == suffix.lower()]


def suffix_target(path: str) -> tuple[str | None, str]:
    """(the installed target whose declared suffix ends the file name ``path``, that suffix), the longest match
    winning, so a two-part suffix (``.null.json``) is matched as a whole; (None, "") when none matches or two
    targets declare the same longest suffix."""
    from pathlib import PurePath

    name = PurePath(str(path)).name.lower()
    matches = [(declared, target) for target, declared in output_suffixes().items()
               if name.endswith(declared.lower()) and len(name) > len(declared)]
    if not matches:
        return None, ""
    longest = max(len(d) for d, _ in matches)
    best = [(d, t) for d, t in matches if len(d) == longest]
    return (best[0][1], best[0][0]) if len(best) == 1 else (None, "")


def _sealed(target: Target) -> Target:
    """``target`` if its declaration is acceptable, else a one-line refusal: an option named like a command's own
    parameter (``RESERVED_OPTIONS``) would shadow that parameter for every target."""
    kind = getattr(target, "options_type", TargetOptions)
    try:
        names = set(declared_options(kind))
    except (TypeError, ValueError) as ex:
        raise SnnccError(f"target {getattr(target, 'name', '?')!r} declares its options wrongly: {ex}",
                         field="--target") from None
    capability_names = {n for record in CAPABILITY_OPTIONS.values() for n in declared_options(record)}
    clash = sorted((names & RESERVED_OPTIONS) - capability_names)
    if clash:
        flags = ", ".join("--" + n.replace("_", "-") for n in clash)
        raise SnnccError(f"target {getattr(target, 'name', '?')!r} declares {flags}, which snncc's commands use "
                         "themselves; the target is not offered (rename its option)", field="--target")
    return target


def _load(ep: EntryPoint) -> Target:
    try:
        found: Target = ep.load()
    except Exception as ex:
        raise SnnccError(f"target {ep.name!r} is installed but does not load ({ep.value}): "
                         f"{type(ex).__name__}: {ex}", field="--target") from None
    return _sealed(found)


def get_target(name: str) -> Target:
    """The registered target ``name`` (the first entry point of that name), or a one-line refusal: not
    installed, its entry point fails to load (the plug-in's own error, named), or its options clash with
    a command's own (``RESERVED_OPTIONS``)."""
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            return _load(ep)
    raise SnnccError(f"unknown target {name!r} (installed: {', '.join(available_targets()) or 'none'})", field="--target")


def default_target() -> Target:
    """``DEFAULT_TARGET``'s target object."""
    return get_target(DEFAULT_TARGET)


def loaded_targets() -> list[Target]:
    """Every registered target that loads, by name (one whose entry point fails is left out here: it
    is refused, with its reason, when a user chooses it)."""
    first: dict[str, EntryPoint] = {}
    for ep in entry_points(group=GROUP):
        first.setdefault(ep.name, ep)
    out = []
    for name in sorted(first):
        try:
            out.append(_load(first[name]))
        except SnnccError:  # a broken plug-in must not take every command's flags down with it
            continue
    return out


# -- the options the registered targets declare ---------------------------------------------------
@dataclass(frozen=True)
class Offer:
    """One flag a command offers: ``name`` (keyword), ``flag``, ``kind`` (bool: a switch; int, float,
    str: a value; str where targets declare different value types: each target converts), the
    merged ``help`` naming the ``targets`` that take it, the ``default`` of a capability's option, and its
    ``path`` role ("input" | "output" | "": see ``Option``)."""

    name: str
    flag: str
    kind: type
    help: str
    targets: tuple[str, ...]
    default: bool | int | float | str | None = None
    path: str = ""


def _declarations(capabilities: Sequence[str]) -> dict[str, list[tuple[str, Option]]]:
    """name -> [(target, declaration)] over the registered targets, for options of ``capabilities``:
    each target's own, and the option records of the capabilities it has (declared once, in base)."""
    found: dict[str, list[tuple[str, Option]]] = {}
    for target in loaded_targets():
        for spec in declared_options(target.options_type).values():
            if set(spec.capabilities) & set(capabilities):
                found.setdefault(spec.name, []).append((target.name, spec))
        for cap in capabilities:
            record = CAPABILITY_OPTIONS.get(cap)
            if record is not None and callable(getattr(target, cap, None)):
                for spec in declared_options(record).values():
                    found.setdefault(spec.name, []).append((target.name, spec))
    return found


def offered_options(capabilities: Sequence[str]) -> list[Offer]:
    """The flags of a command whose verb calls ``capabilities``: one per option name over all registered
    targets (a flag that one target declares as a switch and another as a value is refused)."""
    offers = []
    for name, declared in _declarations(capabilities).items():
        targets = tuple(dict.fromkeys(t for t, _ in declared))
        specs = [s for _, s in declared]
        switches = {s.switch for s in specs}
        if len(switches) > 1:
            both = ", ".join(f"{t} ({'switch' if s.switch else 'value'})" for t, s in declared)
            raise SnnccError(f"targets declare it both as a switch and as a value: {both}", field=specs[0].flag)
        kinds = {s.kind for s in specs}
        kind = kinds.pop() if len(kinds) == 1 else str
        helps = {s.help for s in specs}
        default = specs[0].default if len({s.default for s in specs}) == 1 else None
        shown = f" (default {default})" if default not in (None, False) else ""
        if len(helps) == 1:
            text = f"{specs[0].help}{shown} (--target {', '.join(targets)})"
        else:
            text = "; ".join(f"--target {t}: {s.help.rstrip('.')}" for t, s in declared) + shown
        roles = {s.path for s in specs}
        if len(roles) > 1:
            both = ", ".join(f"{t} ({s.path or 'not a path'})" for t, s in declared)
            raise SnnccError(f"targets declare it with different path roles: {both}", field=specs[0].flag)
        offers.append(Offer(name, specs[0].flag, kind, text, targets, default, roles.pop()))
    return offers


def _check_known(given: Mapping[str, object], capabilities: Sequence[str]) -> None:
    known = {o.name for o in offered_options(capabilities)} | {f.name for f in dataclasses.fields(TargetOptions)}
    for key in given:
        if key not in known:
            raise TypeError(f"no installed target takes an option {key!r} for "
                            f"{', '.join(dict.fromkeys(VERB_OF.get(c, c) for c in capabilities))}")


def target_options(target: Target, given: Given = None, capability: str | None = None) -> TargetOptions:
    """``target``'s option record from the user-given values: ``snncc.targets.base.target_options``
    after checking that every key is an option some installed target declares for some verb (else
    TypeError: a bug)."""
    if isinstance(given, OptionRecord):
        return _target_options(target, given, capability)
    _check_known(given or {}, list(VERB_OF))
    return _target_options(target, given, capability)


@dataclass(frozen=True)
class VerbOptions:
    """What a verb hands its capabilities: the target's record, and each used capability's own."""

    target: TargetOptions
    capabilities: Mapping[str, OptionRecord] = dataclasses.field(default_factory=dict)

    def of(self, kind: type[R]) -> R:
        """The capability record of type ``kind`` (its defaults when none was built)."""
        found = next((r for r in self.capabilities.values() if isinstance(r, kind)), None)
        return found if found is not None else capability_options(kind)


def verb_options(target: Target, given: Mapping[str, object], use: str | Sequence[str],
                 offers: Iterable[str] | None = None) -> VerbOptions:
    """Split the options a verb was given (keyword -> value; None: not given) for the capabilities it
    calls, ``use`` (one, or several: compile with fine-tuning calls two).

    ``offers``: the capabilities whose options the verb's command offers (default ``use``); a key no
    installed target declares for them is a bug (TypeError). A capability's option goes to its record
    when that capability is used, else it is refused in one line; the rest build ``target``'s record
    (``target_options``: validated by the target, refused when it does not take them)."""
    uses = (use,) if isinstance(use, str) else tuple(use)
    offered = list(offers or uses)
    _check_known(given, offered)
    owner = {f.name: cap for cap in offered if cap in CAPABILITY_OPTIONS
             for f in dataclasses.fields(CAPABILITY_OPTIONS[cap])}
    rest: dict[str, object] = {}
    mine: dict[str, dict[str, object]] = {cap: {} for cap in uses if cap in CAPABILITY_OPTIONS}
    for key, value in given.items():
        cap = owner.get(key)
        if cap is None:
            rest[key] = value
        elif cap in mine:
            mine[cap][key] = value
        elif value is not None and value is not False:
            raise SnnccError(f"applies only to {VERB_OF.get(cap, cap)}, not to {VERB_OF.get(uses[0], uses[0])}",
                             field="--" + key.replace("_", "-"))
    records = {cap: capability_options(CAPABILITY_OPTIONS[cap], values) for cap, values in mine.items()}
    return VerbOptions(_target_options(target, rest, uses), records)


def offering(name: str) -> list[str]:
    """The registered targets that offer capability ``name``."""
    return [t.name for t in loaded_targets() if callable(getattr(t, name, None))]


def takers(kind: str) -> list[str]:
    """The registered targets whose ``lower`` takes model records of ``kind`` ("buffered")."""
    return [t.name for t in loaded_targets() if kind in model_kinds(t)]


__all__ = ["Target", "Artefact", "Record", "TargetOptions", "AgreementOptions", "FinetuneOptions", "Offer",
           "VerbOptions", "DEFAULT_TARGET", "RESERVED_OPTIONS", "default_target", "suffix_target",
           "get_target", "available_targets", "loaded_targets", "capability", "target_options", "verb_options",
           "offered_options", "model_kinds", "offering", "takers", "output_suffixes", "targets_for_suffix"]
