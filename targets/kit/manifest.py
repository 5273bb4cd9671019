"""A manifest directory: an artefact that is a directory of files described by one ``manifest.json``.

The manifest names the artefact's format (``"format": "snncc-<target>-artefact"``), lists its files
and, where the format records them, their SHA-256 (``"files": {name: sha256}``), and the model it came
from (``"source": {"file": ..., "sha256": ...}``: ``source_identity``). One ``ManifestFormat`` per target
says which format tag is its own and which files belong to an artefact; it then

    write(path, files)      writes the files atomically (``kit.writing.atomic_dir``), replacing an existing
                            directory only when it is an earlier artefact of this format holding nothing else
    manifest(path)          the manifest when ``path`` is a directory with this format's manifest, else None
                            (a size-bounded regular file; nothing else is read)
    open(path)              the manifest, after checking that every listed file is a regular file inside the
                            directory and, where the manifest records its SHA-256, has those bytes
    identify(path)          ``kit.artefact.ArtefactIdentity`` (the capability ``identify``), or None; its ``model``
                            is the manifest's ``model_key`` entry (``kit.artefact.model_record`` of the loaded model)
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snncc.errors import SnnccError
from snncc.targets.kit.artefact import ArtefactIdentity, file_sha256, is_plain_directory, is_plain_file, member
from snncc.targets.kit.writing import atomic_dir, foreign_entries

MANIFEST = "manifest.json"
MAX_MANIFEST_BYTES = 1 << 22


def source_identity(metadata: Mapping[str, Any], source: str | None) -> dict[str, Any]:
    """What an artefact records of the model it came from: the model file (the graph's ``source_file``, else
    ``source``) and its SHA-256 (``source_sha256``, None where the model recorded none)."""
    return {"file": metadata.get("source_file") or source, "sha256": metadata.get("source_sha256")}


def manifest_bytes(manifest: Mapping[str, Any], **dumps: Any) -> bytes:
    """The manifest as written: JSON indented by 2, one trailing newline."""
    return (json.dumps(manifest, indent=2, **dumps) + "\n").encode("utf-8")


def _listed_hashes(manifest: Mapping[str, Any]) -> dict[str, str | None]:
    files = manifest.get("files")
    if isinstance(files, dict):
        return {str(k): (v if isinstance(v, str) else None) for k, v in files.items()}
    return {}


@dataclass(frozen=True)
class ManifestFormat:
    """One target's manifest-directory format (module doc).

    ``files(manifest)``: the artefact's own file names with the SHA-256 the manifest records for each (None
    where it records none); default: the manifest's ``files`` mapping plus ``manifest.json``.
    ``own_extra(manifest)``: further names a user may find there that the artefact's tools write (Jetson's
    TensorRT ``.plan`` engines): tolerated on replacement, not part of the artefact.
    ``describe(manifest)``: the identity's description. ``executable``: files written with mode 0755."""

    format: str
    target: str
    kind: str                                   # "a Xylo artefact directory": for refusals
    files: Callable[[Mapping[str, Any]], Mapping[str, str | None]] = _listed_hashes
    own_extra: Callable[[Mapping[str, Any]], set[str]] = field(default=lambda manifest: set())
    describe: Callable[[Mapping[str, Any]], str] = field(default=lambda manifest: "")
    executable: tuple[str, ...] = ()
    manifest_name: str = MANIFEST
    model_key: str = "model"          # where the manifest holds ``kit.artefact.model_record`` of the loaded model
    where: Callable[[Mapping[str, Any], str], str] = field(
        default=lambda manifest, name: f"{MANIFEST}/files/{name}")   # the manifest entry that lists ``name``

    # -- reading --------------------------------------------------------------------------------------
    def manifest(self, path: str | os.PathLike) -> dict[str, Any] | None:
        """The parsed manifest if ``path`` is a directory (not a link) whose manifest (a regular file, not a
        link, at most 4 MiB) declares this format; else None. Reads nothing else."""
        path = Path(path)
        if not is_plain_directory(path):
            return None
        file = path / self.manifest_name
        try:
            if not is_plain_file(file) or file.stat().st_size > MAX_MANIFEST_BYTES:
                return None
            manifest = json.loads(file.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return manifest if isinstance(manifest, dict) and manifest.get("format") == self.format else None

    def own_files(self, manifest: Mapping[str, Any]) -> dict[str, str | None]:
        """The artefact's files (name -> recorded SHA-256 or None), the manifest always among them."""
        listed = dict(self.files(manifest))
        listed.setdefault(self.manifest_name, None)
        return dict(sorted(listed.items()))

    def open(self, path: str | os.PathLike) -> dict[str, Any]:
        """The manifest of the artefact at ``path`` after checking every file it lists: a regular file inside
        the directory (no link), with the recorded SHA-256 where there is one; else one line naming the file."""
        path = Path(path)
        if not path.exists() and not path.is_symlink():
            raise SnnccError("does not exist", file=str(path), field="artefact")
        if not is_plain_directory(path):
            raise SnnccError(f"is not {self.kind}", file=str(path), field="artefact")
        member(path, self.manifest_name)
        manifest = self.manifest(path)
        if manifest is None:
            raise SnnccError(f"has no readable {self.manifest_name} of {self.kind}", file=str(path),
                             field=self.manifest_name)
        for name, recorded in self.own_files(manifest).items():
            if not isinstance(name, str):
                raise SnnccError("the manifest lists a file name that is not text", file=str(path),
                                 field=self.manifest_name)
            try:
                file = member(path, name)
            except SnnccError as err:       # named by the manifest entry that lists it
                shown = name.encode("unicode_escape").decode("ascii")
                raise SnnccError(f"lists '{shown}', which {err.rule}", file=str(path),
                                 field=self.where(manifest, name)) from None
            if recorded is not None and file_sha256(file) != recorded:
                raise SnnccError(f"its SHA-256 differs from the one {self.manifest_name} records (the file was changed)",
                                 file=str(file), field=name)
        return manifest

    def identify(self, path: str | os.PathLike) -> ArtefactIdentity | None:
        """The identity of this format's artefact at ``path`` (its files, the source hash it records), or None.
        Reads the manifest only."""
        manifest = self.manifest(path)
        if manifest is None:
            return None
        source = manifest.get("source") if isinstance(manifest.get("source"), dict) else {}
        try:
            names = sorted(self.own_files(manifest))
            description = self.describe(manifest)
        except (KeyError, TypeError, AttributeError, ValueError):
            names, description = [self.manifest_name], self.kind
        model = manifest.get(self.model_key)
        return ArtefactIdentity(target=self.target, path=str(path), files=names,
                                source_sha256=source.get("sha256") or None, source_file=source.get("file") or None,
                                description=description,
                                model=model if isinstance(model, dict) and "graph_sha256" in model else None)

    # -- writing --------------------------------------------------------------------------------------
    def replace_refusal(self, directory: str | os.PathLike) -> str | None:
        """None if ``directory`` is an earlier artefact of this format holding only its own regular files (and
        the tolerated extras); else why it may not be replaced."""
        directory = Path(directory)
        manifest = self.manifest(directory)
        if manifest is None:
            return f"it has no readable {self.manifest_name} of {self.kind}"
        try:
            ours = set(self.own_files(manifest)) | set(self.own_extra(manifest))
        except (KeyError, TypeError, AttributeError, ValueError):
            return f"its {self.manifest_name} does not list its files"
        return foreign_entries(directory, ours)

    def write(self, path: str | os.PathLike, files: Mapping[str, bytes]) -> None:
        """Write ``files`` (name -> bytes, in order) as the artefact directory ``path``, atomically."""
        with atomic_dir(Path(path), replaceable=self.replace_refusal) as tmp:
            for name, data in files.items():
                (tmp / name).write_bytes(data)
                if name in self.executable:
                    os.chmod(tmp / name, 0o755)


__all__ = ["ManifestFormat", "MANIFEST", "source_identity", "manifest_bytes"]
