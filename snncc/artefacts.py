"""Which installed target wrote an artefact, and whether it came from a given model.

A target recognises its own artefacts (capability ``identify(path) -> ArtefactIdentity | None``), so a
third-party target's artefact is found the same way as snncc's. The identity and the artefact's
SHA-256 are the kit's (``snncc.targets.kit.artefact``); this module asks every installed target.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from snncc.errors import SnnccError
from snncc.targets.kit.artefact import (  # noqa: F401  (the names the verbs use)
    DIRECTORY_RULE, FILE_RULE, ArtefactIdentity, artefact_sha256, file_sha256,
)


def identify_own(target: Any, path: str | Path) -> ArtefactIdentity | None:
    """``target``'s identity of its artefact at ``path`` (capability ``identify``), or None when the target
    does not identify artefacts or does not recognise this one."""
    recognise = getattr(target, "identify", None)
    if not callable(recognise):
        return None
    found = recognise(Path(path))
    return found if isinstance(found, ArtefactIdentity) else None


VERBS = {"emulate": "`snncc emulate` runs it", "run": "`snncc run` runs it", "map": "`snncc map` maps it",
         "estimate": "`snncc report --energy` estimates it", "bench": "`snncc bench` times it",
         "agree": "`snncc check MODEL --artefact` measures it",
         "check": "`snncc check MODEL --artefact --data D` measures it"}


def recognised(path: str | Path) -> list[tuple[Any, ArtefactIdentity]]:
    """(target, identity) of every installed target that recognises ``path`` as its artefact (a target whose
    ``identify`` refuses a damaged file of its own is counted as recognising it: its reader names the damage)."""
    from snncc.targets import loaded_targets

    found = []
    for tgt in loaded_targets():
        try:
            identity = identify_own(tgt, path)
        except SnnccError:
            identity = ArtefactIdentity(tgt.name, str(path), description=f"a damaged {tgt.name} artefact")
        if identity is not None:
            found.append((tgt, identity))
    return found


def readers(target: Any) -> str:
    """What snncc does with ``target``'s artefacts, by the capabilities it has ("`snncc emulate` runs it, ...")."""
    said = list(dict.fromkeys(VERBS["agree" if cap == "check" and callable(getattr(target, "agree", None)) else cap]
                              for cap in VERBS if callable(getattr(target, cap, None))))
    return ", ".join(said) or "no snncc command reads it"


def artefact_note(path: str | Path) -> str | None:
    """"is <description> (target NAME): <what reads it>" when an installed target recognises ``path``, else None
    (for refusals that say what was given instead of what was expected)."""
    found = recognised(path)
    if not found:
        return None
    tgt, identity = found[0]
    what = identity.description or f"a {tgt.name} artefact"
    article = "" if what.split(" ", 1)[0].lower() in ("a", "an", "the") else "a "
    return f"is {article}{what} (target {tgt.name}): {readers(tgt)}"


def target_for(path: str | Path, target: str | None, capability: str, field: str = "artefact") -> Any:
    """The target whose artefact ``path`` is (capability ``identify``), which must offer ``capability``; with
    ``target`` (the user's --target) that target, which must agree with the artefact's. Refused in one line:
    a path that does not exist, one no installed target recognises, one recognised by several (pass
    --target), or an artefact whose target has no such capability (naming the target and what reads it)."""
    from snncc.targets import get_target, loaded_targets

    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise SnnccError("file does not exist", file=str(path), field=field)
    found = recognised(path)
    if target is not None:
        chosen = get_target(target)
        others = [t for t, _ in found if t.name != chosen.name]
        if others and not any(t.name == chosen.name for t, _ in found):
            raise SnnccError(f"is a {others[0].name} artefact, not {chosen.name}'s (its target follows from the "
                             "artefact; leave --target out)", file=str(path), field="--target")
        _refuse_lacking(chosen, path, capability, field)
        return chosen
    if not found:
        asked = ", ".join(t.name for t in loaded_targets() if callable(getattr(t, "identify", None)))
        raise SnnccError(f"is not an artefact any installed target recognises ({asked} were asked)", file=str(path),
                         field=field)
    able = [(t, i) for t, i in found if callable(getattr(t, capability, None))]
    if not able:
        _refuse_lacking(found[0][0], path, capability, field)
    if len(able) > 1:
        raise SnnccError(f"recognised by several targets ({', '.join(t.name for t, _ in able)}); pass --target",
                         file=str(path), field=field)
    return able[0][0]


def _refuse_lacking(target: Any, path: Path, capability: str, field: str) -> None:
    if not callable(getattr(target, capability, None)):
        raise SnnccError(f"is a {target.name} artefact; the {target.name} target has no {capability} "
                         f"({readers(target)})", file=str(path), field=field)


def identify(path: str | Path, target: str | None = None) -> tuple[Any, ArtefactIdentity]:
    """(target object, identity) of the artefact at ``path``, asking every installed target that offers
    ``identify``. ``target`` (the user's --target) must agree with the artefact's, else one line."""
    from snncc.targets import loaded_targets

    path = Path(path)
    if not path.exists():
        raise SnnccError("does not exist", file=str(path), field="--artefact")
    found = []
    for tgt in loaded_targets():
        identity = identify_own(tgt, path)
        if identity is not None:
            found.append((tgt, identity))
    if not found:
        offering = [t.name for t in loaded_targets() if callable(getattr(t, "identify", None))]
        raise SnnccError(f"not an artefact any installed target recognises ({', '.join(offering)} were asked)",
                         file=str(path), field="--artefact")
    if len(found) > 1 and target is None:
        raise SnnccError(f"recognised by several targets ({', '.join(t.name for t, _ in found)}); pass --target",
                         file=str(path), field="--artefact")
    if target is not None:
        match = [(t, i) for t, i in found if t.name == target]
        if not match:
            raise SnnccError(f"the artefact is a {found[0][0].name} artefact, not {target}'s (its target follows from "
                             "the artefact; leave --target out)", field="--target")
        return match[0]
    return found[0]


def check_source(identity: ArtefactIdentity, graph, model: str | Path) -> str | None:
    """Refuse an artefact compiled from another model file (their recorded SHA-256 differ), or from this file
    loaded with other model options (another dt, reset or stated length: the graph fingerprints the artefact
    records and the model gives differ, ``kit.artefact.model_record``); the note to print when the artefact
    records no source hash or no fingerprint (None when everything matches)."""
    from snncc.targets.kit.artefact import model_record

    have = graph.metadata.get("source_sha256")
    recorded = identity.source_sha256
    notes = []
    if not recorded:
        notes.append("the artefact records no source hash: not compared with the model file")
    elif not have:
        notes.append("the model records no source hash: not compared with the artefact")
    elif recorded != have:
        raise SnnccError(f"was compiled from another model (it records source SHA-256 {recorded[:16]}..., "
                         f"{Path(model).name} has {have[:16]}...)", file=identity.path, field="source_sha256")
    compiled = identity.model
    if not isinstance(compiled, dict) or not compiled.get("graph_sha256"):
        notes.append("the artefact records no model fingerprint (an older snncc): the model options it was compiled "
                     "with (dt, reset) were not compared with these")
    else:
        given = model_record(graph)
        if given["graph_sha256"] != compiled["graph_sha256"]:
            raise SnnccError(_option_difference(compiled, given, Path(model).name), file=identity.path, field="model")
    return "; ".join(notes) or None


def _option_difference(compiled: dict, given: dict, name: str) -> str:
    """Why the model as loaded now is not the model the artefact was compiled from, in the user's flags."""
    if compiled.get("dt") is not None and given.get("dt") != compiled.get("dt"):
        return (f"was compiled from {name} at --dt {compiled['dt']:g}; the model given here has dt {given['dt']:g}: "
                f"pass --dt {compiled['dt']:g} (or compile the model again)")
    before, now = compiled.get("resets") or {}, given.get("resets") or {}
    if before != now:
        changed = sorted(k for k in set(before) | set(now) if before.get(k) != now.get(k))
        first = changed[0] if changed else "?"
        return (f"was compiled from {name} with population {first!r} resetting by {before.get(first, '?')}; loaded here "
                f"it resets by {now.get(first, '?')}: pass the --reset the artefact was compiled with")
    if compiled.get("recording_length_s") != given.get("recording_length_s"):
        return (f"was compiled from {name} stating a recording length of {compiled.get('recording_length_s')} s; the "
                f"model given here states {given.get('recording_length_s')}")
    return (f"was compiled from {name} loaded with other options (--params?): its graph fingerprint "
            f"{compiled['graph_sha256'][:16]}... differs from the model given here ({given['graph_sha256'][:16]}...)")


def not_a_model_file(path: str | Path, field: str = "model") -> SnnccError:
    """The refusal for ``path`` given where a model file was expected: it does not exist, it is an artefact
    (named, with the commands that read it), a directory, or not a regular file."""
    p = Path(path)
    if not p.exists():
        return SnnccError("file does not exist", file=str(p), field=field)
    note = artefact_note(p)
    if note is not None:
        return SnnccError(f"{note}; it is not a model file", file=str(p), field=field)
    if p.is_dir():
        return SnnccError("is a directory, not a model file", file=str(p), field=field)
    return SnnccError("is not a regular file (a device or pipe), not a model file", file=str(p), field=field)
