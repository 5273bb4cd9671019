"""A written artefact's identity and hash, and the rule that its files are regular files inside it.

A target recognises its own artefacts (capability ``identify(path) -> ArtefactIdentity | None``); the
identity names the files that make the artefact (a directory artefact lists them in its manifest) and
the model source hash the artefact records.

The hash (``artefact_sha256``), stated so anyone can recompute it:

    a file:       SHA-256 of its bytes (``sha256sum FILE``)
    a directory:  SHA-256 of the text of one line per artefact file, sorted by name,
                  "<sha256 of the file>  <name>\\n" (``sha256sum NAMES | LC_ALL=C sort -k 2 | sha256sum``
                  in the directory, with the names the identity lists)

Every file of an artefact is a regular file inside it: a symbolic link (even one pointing into the
artefact), a device, a directory or a name that leaves the directory (``..``, an absolute path) is
refused in one line before anything is read through it (``member``).
"""

from __future__ import annotations

import hashlib
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

from snncc.atomic import file_sha256
from snncc.errors import SnnccError

FILE_RULE = "SHA-256 of the file's bytes"
DIRECTORY_RULE = ("SHA-256 over the artefact's files: one line '<sha256>  <name>' per file, sorted by name "
                  "(sha256sum NAMES | LC_ALL=C sort -k 2 | sha256sum)")


@dataclass
class ArtefactIdentity:
    """What a target knows of one of its written artefacts, without running it."""

    target: str                                       # the target's registered name
    path: str
    files: list[str] = field(default_factory=list)    # a directory artefact's files (relative names); [] for a file
    source_sha256: str | None = None                  # the model file's hash the artefact records (None: not recorded)
    source_file: str | None = None
    description: str = ""                             # e.g. "Loihi bundle (HDF5, netx layout)"
    model: dict | None = None                         # ``model_record`` of the graph it was lowered from (None: not
                                                      # recorded, an artefact of an older snncc)

    @property
    def is_directory(self) -> bool:
        return Path(self.path).is_dir()


def model_record(graph) -> dict:   # noqa: ANN001 (an IR Graph)
    """What an artefact records of the model as loaded (``snncc check --artefact`` compares it with the model it is
    given): the graph's fingerprint (``snncc.ir.serialize.graph_fingerprint``: every weight, delay, reset, dt and
    stated length), its dt, and each LIF population's reset."""
    from snncc.ir.nodes import LIF
    from snncc.ir.serialize import graph_fingerprint

    return {"graph_sha256": graph_fingerprint(graph), "dt": float(graph.dt),
            "resets": {name: str(op.reset) for name, op in graph.items() if isinstance(op, LIF)},
            "recording_length_s": graph.metadata.get("recording_length_s")}


def sha256_bytes(data: bytes) -> str:
    """Hex SHA-256 of ``data``."""
    return hashlib.sha256(data).hexdigest()


def member(directory: str | os.PathLike, name: str, *, field_name: str | None = None) -> Path:
    """``directory / name`` when it is a regular file inside ``directory`` (not a symbolic link, not through
    one, no ``..`` or absolute name); else a one-line refusal naming the file. A missing file is refused
    too (``missing``)."""
    directory = Path(directory)
    shown = field_name or name
    parts = Path(name).parts
    if not name or Path(name).is_absolute() or ".." in parts or any(p in ("", ".") for p in parts):
        raise SnnccError("is not a file name inside the artefact directory", file=str(directory), field=shown)
    path = directory
    for part in parts:
        path = path / part
        try:
            mode = os.lstat(path).st_mode
        except FileNotFoundError:
            raise SnnccError("missing", file=str(directory / name), field=shown) from None
        except OSError as ex:
            raise SnnccError(f"cannot be read ({os.strerror(ex.errno or 0) or ex})", file=str(directory / name),
                             field=shown) from None
        if stat.S_ISLNK(mode):
            raise SnnccError("is a symbolic link (it may lead outside the artefact); an artefact's files are regular "
                             "files inside its directory", file=str(path), field=shown)
    if not stat.S_ISREG(mode):
        raise SnnccError("is not a regular file; an artefact's files are regular files inside its directory",
                         file=str(path), field=shown)
    return path


def is_plain_file(path: str | os.PathLike) -> bool:
    """A regular file that is not a symbolic link."""
    try:
        return stat.S_ISREG(os.lstat(path).st_mode)
    except OSError:
        return False


def is_plain_directory(path: str | os.PathLike) -> bool:
    """A directory that is not a symbolic link."""
    try:
        return stat.S_ISDIR(os.lstat(path).st_mode)
    except OSError:
        return False


def artefact_sha256(path: str | os.PathLike, files: list[str] | None = None) -> tuple[str, str]:
    """(hex digest, the rule that made it) of the artefact at ``path`` (see the module docstring).

    ``files``: a directory artefact's file names (its identity's); None takes every regular file in
    it (a target that lists none). A listed file that is missing, a link or not a regular file is
    refused (``member``)."""
    path = Path(path)
    if path.is_file():
        return file_sha256(path), FILE_RULE
    if not path.is_dir():
        raise SnnccError("does not exist", file=str(path), field="artefact")
    if files:
        names = sorted(files)
    else:
        names = sorted(str(p.relative_to(path)) for p in path.rglob("*") if p.is_file() or p.is_symlink())
    lines = [f"{file_sha256(member(path, name))}  {name}\n" for name in names]
    return hashlib.sha256("".join(lines).encode("utf-8")).hexdigest(), DIRECTORY_RULE


__all__ = ["ArtefactIdentity", "model_record", "FILE_RULE", "DIRECTORY_RULE", "artefact_sha256", "file_sha256", "sha256_bytes",
           "member", "is_plain_file", "is_plain_directory"]
