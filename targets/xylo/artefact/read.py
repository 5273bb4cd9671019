"""A written Xylo artefact read back: its manifest and spec, each file checked by the kit's manifest format
(a regular file inside the directory, never a link, with the SHA-256 the manifest records) and the manifest's
entries checked before they are used; anything else is refused in one line naming the file and the field."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from snncc.targets.kit import SnnccError
from snncc.targets.kit.artefact import ArtefactIdentity, member
from snncc.targets.xylo.artefact.format import MANIFEST, MANIFEST_FORMAT, SPEC


@dataclass
class WrittenXylo:
    path: Path
    manifest: dict[str, Any]
    spec: Any                  # XyloSpec

    @property
    def input_pad(self) -> int:
        return int(self.manifest["feed"]["input_pad"])

    @property
    def output_lag(self) -> int:
        return int(self.manifest["feed"]["output_lag"])

    @property
    def chip(self) -> str:
        return str(self.manifest["chip"]["key"])


def read_manifest(path: str | os.PathLike) -> dict[str, Any] | None:
    """The artefact's manifest if ``path`` is a directory holding an snncc Xylo manifest, else None (reads the
    manifest only)."""
    return MANIFEST_FORMAT.manifest(path)


def read_artefact(path: str | os.PathLike) -> WrittenXylo:
    """Manifest and spec of the artefact directory ``path``; every listed file checked (``ManifestFormat.open``)."""
    from snncc.targets.xylo.spec import XyloSpec

    path = Path(path)
    manifest = MANIFEST_FORMAT.open(path)
    try:
        manifest["files"][SPEC], manifest["feed"]["input_pad"], manifest["feed"]["output_lag"]
        manifest["chip"]["key"]
    except (KeyError, TypeError):
        raise SnnccError("the manifest lacks files, feed or chip entries", file=str(path / MANIFEST),
                         field=MANIFEST) from None
    return WrittenXylo(path, manifest, XyloSpec.load_npz(member(path, SPEC)))


def identify_artefact(path: str | os.PathLike) -> ArtefactIdentity | None:
    """``ArtefactIdentity`` of the Xylo artefact at ``path`` (its four files, the source model's hash it records, the
    model record ``kit.artefact.model_record`` as ``model``: None for an artefact of an older snncc), or None when
    ``path`` is no directory with an snncc Xylo manifest. Reads the manifest only."""
    identity = MANIFEST_FORMAT.identify(path)
    if identity is not None:
        manifest = MANIFEST_FORMAT.manifest(path) or {}
        model = manifest.get("model")
        identity.model = model if isinstance(model, dict) else None
    return identity
