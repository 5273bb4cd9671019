"""Written artefacts: which target wrote one, its SHA-256, and whether it came from a given model.

A target recognises its own artefacts (capability ``identify(path) -> ArtefactIdentity | None``),
so a third-party target's artefact is found the same way as snncc's. The identity names the files
that make the artefact (a directory artefact lists them in its manifest) and the model source hash
the artefact records.

The hash (``artefact_sha256``), stated so anyone can recompute it:

    a file:       SHA-256 of its bytes (``sha256sum FILE``)
    a directory:  SHA-256 of the text of one line per artefact file, sorted by name,
                  "<sha256 of the file>  <name>\\n" (``sha256sum NAMES | LC_ALL=C sort -k 2 | sha256sum``
                  in the directory, with the names the identity lists)
"""

from __future__ import annotations

import contextlib
import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

from snncc.errors import SnnccError

FILE_RULE = "SHA-256 of the file's bytes"
DIRECTORY_RULE = ("SHA-256 over the artefact's files: one line '<sha256>  <name>' per file, sorted by name "
                  "(sha256sum NAMES | LC_ALL=C sort -k 2 | sha256sum)")
CHUNK = 1 << 20


@dataclass
class ArtefactIdentity:
    """What a target knows of one of its written artefacts, without running it."""

    target: str                                       # the target's registered name
    path: str
    files: list[str] = field(default_factory=list)    # a directory artefact's files (relative names); [] for a file
    source_sha256: str | None = None                  # the model file's hash the artefact records (None: not recorded)
    source_file: str | None = None
    description: str = ""                             # e.g. "Loihi bundle (HDF5, netx layout)"

    @property
    def is_directory(self) -> bool:
        return Path(self.path).is_dir()


def file_sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(CHUNK), b""):
            h.update(block)
    return h.hexdigest()


def artefact_sha256(path: str | Path, files: list[str] | None = None) -> tuple[str, str]:
    """(hex digest, the rule that made it) of the artefact at ``path`` (see the module docstring).

    ``files``: a directory artefact's file names (its identity's); None takes every regular file in
    it (a target that lists none)."""
    path = Path(path)
    if path.is_file():
        return file_sha256(path), FILE_RULE
    if not path.is_dir():
        raise SnnccError("does not exist", file=str(path), field="artefact")
    names = sorted(files) if files else sorted(str(p.relative_to(path)) for p in path.rglob("*") if p.is_file())
    lines = []
    for name in names:
        member = path / name
        if not member.is_file():
            raise SnnccError(f"the artefact lists '{name}', which is missing", file=str(path), field=name)
        lines.append(f"{file_sha256(member)}  {name}\n")
    return hashlib.sha256("".join(lines).encode("utf-8")).hexdigest(), DIRECTORY_RULE


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


@contextlib.contextmanager
def compiled_artefact(target: Any, graph, options: Any = None) -> Iterator[Path]:
    """Yields the path of the artefact ``snncc compile`` would write for ``graph`` (the target's
    ``lower`` with ``options``; keys that are no field of the target's option record, such as a
    check's ``mode``, are left out), written to a temporary directory that is removed afterwards."""
    import dataclasses
    import tempfile

    from snncc.targets import capability, target_options
    from snncc.targets.base import TargetOptions

    if not isinstance(options, TargetOptions):
        kind = getattr(target, "options_type", TargetOptions)
        names = {f.name for f in dataclasses.fields(kind)}
        options = target_options(target, {k: v for k, v in dict(options or {}).items() if k in names}, "lower")
    artefact = capability(target, "lower")(graph, options)
    with tempfile.TemporaryDirectory(prefix="snncc-check-") as tmp:
        path = Path(tmp) / f"artefact.{target.name}"
        artefact.write(path)
        yield path
