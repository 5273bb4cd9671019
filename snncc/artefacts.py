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


def target_for(path: str | Path, target: str | None, capability: str, default: str = "loihi") -> Any:
    """The target ``target`` names; None: the one installed target that has ``capability`` and recognises the
    artefact at ``path`` (capability ``identify``), else ``default`` (whose reader then says in one line what
    the file is, or is not)."""
    from snncc.targets import get_target, loaded_targets

    if target is not None:
        return get_target(target)
    path = Path(path)
    if path.exists():
        found = []
        for t in loaded_targets():
            if not callable(getattr(t, capability, None)):
                continue
            try:
                if identify_own(t, path) is not None:
                    found.append(t)
            except SnnccError:            # a damaged file: the default reader names it in its refusal
                continue
        if len(found) == 1:
            return found[0]
    return get_target(default)


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
    """Refuse an artefact compiled from another model file (their recorded SHA-256 differ); the note
    to print when the artefact records no source hash (None when they match)."""
    have = graph.metadata.get("source_sha256")
    recorded = identity.source_sha256
    if not recorded:
        return "the artefact records no source hash: not compared with the model file"
    if not have:
        return "the model records no source hash: not compared with the artefact"
    if recorded != have:
        raise SnnccError(f"was compiled from another model (it records source SHA-256 {recorded[:16]}..., "
                         f"{Path(model).name} has {have[:16]}...)", file=identity.path, field="source_sha256")
    return None
