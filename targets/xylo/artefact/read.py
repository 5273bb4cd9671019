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

    @property
    def sample_steps(self) -> int | None:
        """Steps of a sample the artefact was compiled for (None: an artefact of an older snncc records none)."""
        found = self.manifest["feed"].get("sample_steps")
        return None if found is None else int(found)

    def runnable(self) -> WrittenXylo:
        """The artefact, after checking its spec against its chip's limits (the chip refuses what breaks them, so
        neither snncc's emulator nor a report runs it): one line naming spec.npz, the field and the limit."""
        self.spec.check_chip(self.chip, file=str(self.path / SPEC))
        return self


def read_manifest(path: str | os.PathLike) -> dict[str, Any] | None:
    """The artefact's manifest if ``path`` is a directory holding an snncc Xylo manifest, else None (reads the
    manifest only)."""
    return MANIFEST_FORMAT.manifest(path)


def _whole(manifest: Path, value: Any, field: str, minimum: int) -> int:
    """A whole number of the manifest (a JSON integer, not a boolean, a fraction or text) from ``minimum`` to
    ``MAX_TIME_STEPS``; else one line naming the manifest and the field."""
    from snncc.targets.kit.compute import MAX_TIME_STEPS

    if isinstance(value, bool) or not isinstance(value, int) or not minimum <= value <= MAX_TIME_STEPS:
        raise SnnccError(f"must be a whole number from {minimum} to {MAX_TIME_STEPS:,}, got {value!r}",
                         file=str(manifest), field=field)
    return value


def checked_manifest(path: Path, manifest: dict[str, Any]) -> dict[str, Any]:
    """``manifest`` after checking every entry the Xylo target reads from it; one line naming the first bad one."""
    from snncc.targets.xylo.chip import CHIPS

    file = path / MANIFEST
    for key in ("files", "feed", "chip", "quantization"):
        if not isinstance(manifest.get(key), dict):
            raise SnnccError("missing, or not a JSON object", file=str(file), field=key)
    if not isinstance(manifest["files"].get(SPEC), str):
        raise SnnccError("missing: the SHA-256 of spec.npz", file=str(file), field=f"files.{SPEC}")
    feed = manifest["feed"]
    _whole(file, feed.get("input_pad"), "feed.input_pad", 0)
    _whole(file, feed.get("output_lag"), "feed.output_lag", 0)
    if feed.get("sample_steps") is not None:
        _whole(file, feed["sample_steps"], "feed.sample_steps", 1)
    key = manifest["chip"].get("key")
    if not isinstance(key, str) or key not in CHIPS:
        raise SnnccError(f"must be one of {', '.join(CHIPS)}, got {key!r}", file=str(file), field="chip.key")
    rule = manifest["quantization"].get("rule")
    if not isinstance(rule, str):
        raise SnnccError("must be text (the placement rule)", file=str(file), field="quantization.rule")
    changes = manifest["quantization"].get("changes", [])
    if not isinstance(changes, list) or not all(isinstance(c, str) for c in changes):
        raise SnnccError("must be a list of text lines", file=str(file), field="quantization.changes")
    real_time = manifest.get("real_time", {})
    rates = real_time.get("rates", {}) if isinstance(real_time, dict) else None
    if not isinstance(rates, dict) or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                              and 0.0 <= v <= 1.0 for v in rates.values()):
        raise SnnccError("must hold event rates from 0 to 1", file=str(file), field="real_time.rates")
    return manifest


def read_artefact(path: str | os.PathLike) -> WrittenXylo:
    """Manifest and spec of the artefact directory ``path``: every listed file a regular file inside it with its
    recorded SHA-256 (``ManifestFormat.open``), every manifest entry the target reads checked (``checked_manifest``);
    nothing is read through a link or outside the directory."""
    from snncc.targets.xylo.spec import XyloSpec

    path = Path(path)
    manifest = checked_manifest(path, MANIFEST_FORMAT.open(path))
    return WrittenXylo(path, manifest, XyloSpec.load_npz(member(path, SPEC)))


def _claims_to_be_ours(path: Path) -> bool:
    """A directory named like a Xylo artefact (``.xylo``) whose manifest is not a regular file inside it."""
    from snncc.targets.kit.artefact import is_plain_directory

    manifest = path / MANIFEST
    return path.suffix == ".xylo" and is_plain_directory(path) and (manifest.is_symlink() or
                                                                   (manifest.exists() and not manifest.is_file()))


def identify_artefact(path: str | os.PathLike) -> ArtefactIdentity | None:
    """``ArtefactIdentity`` of the Xylo artefact at ``path`` (its four files, the source model's hash it records, the
    model record ``kit.artefact.model_record`` as ``model``: None for an artefact of an older snncc), or None when
    ``path`` is no directory with an snncc Xylo manifest. Reads the manifest only; a directory named ``.xylo``
    whose manifest is a symbolic link (or not a regular file) is refused in one line, nothing read through it."""
    identity = MANIFEST_FORMAT.identify(path)
    if identity is None and _claims_to_be_ours(Path(path)):
        member(path, MANIFEST)            # a directory named .xylo whose manifest is a link: refused, nothing read
    if identity is not None:
        manifest = MANIFEST_FORMAT.manifest(path) or {}
        model = manifest.get("model")
        identity.model = model if isinstance(model, dict) else None
    return identity
