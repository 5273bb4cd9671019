"""A written Xylo artefact read back: its manifest and spec, each file checked against the hashes the
manifest records; anything else is refused in one line naming the file."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from snncc.errors import SnnccError
from snncc.targets.xylo.artefact import FORMAT, MANIFEST, SPEC


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


def read_manifest(path: str | Path) -> dict[str, Any] | None:
    """The artefact's manifest if ``path`` is a directory holding an snncc Xylo manifest, else None."""
    path = Path(path)
    if not path.is_dir():
        return None
    try:
        manifest = json.loads((path / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return manifest if isinstance(manifest, dict) and manifest.get("format") == FORMAT else None


def read_artefact(path: str | Path) -> WrittenXylo:
    """Manifest and spec of the artefact directory ``path``; spec.npz must match the SHA-256 recorded."""
    from snncc.atomic import file_sha256
    from snncc.targets.xylo.spec import XyloSpec

    path = Path(path)
    if not path.is_dir():
        raise SnnccError("not a Xylo artefact directory (snncc compile --target xylo -o DIR writes one)",
                         file=str(path), field="artefact")
    manifest = read_manifest(path)
    if manifest is None:
        raise SnnccError(f"has no readable {MANIFEST} of an snncc Xylo artefact", file=str(path), field=MANIFEST)
    try:
        recorded = manifest["files"][SPEC]
        manifest["feed"]["input_pad"], manifest["feed"]["output_lag"], manifest["chip"]["key"]
    except (KeyError, TypeError):
        raise SnnccError("the manifest lacks files, feed or chip entries", file=str(path / MANIFEST),
                         field=MANIFEST) from None
    spec_path = path / SPEC
    if not spec_path.is_file():
        raise SnnccError("missing", file=str(spec_path), field=SPEC)
    if file_sha256(spec_path) != recorded:
        raise SnnccError("its SHA-256 differs from the one manifest.json records (the file was changed)",
                         file=str(spec_path), field=SPEC)
    return WrittenXylo(path, manifest, XyloSpec.load_npz(spec_path))


def identify_artefact(path: str | Path):
    """``snncc.artefacts.ArtefactIdentity`` of the Xylo artefact at ``path`` (its four files, the source model's
    hash it records), or None when ``path`` is no directory with an snncc Xylo manifest. Reads the manifest only."""
    from snncc.artefacts import ArtefactIdentity
    from snncc.targets.xylo.artefact import FILES

    manifest = read_manifest(path)
    if manifest is None:
        return None
    source = manifest.get("source") if isinstance(manifest.get("source"), dict) else {}
    chip = manifest.get("chip") if isinstance(manifest.get("chip"), dict) else {}
    return ArtefactIdentity(target="xylo", path=str(path), files=sorted(FILES),
                            source_sha256=source.get("sha256") or None, source_file=source.get("file") or None,
                            description=f"Xylo artefact ({chip.get('name', 'Xylo')}: spec.npz for XyloSim / samna)")
