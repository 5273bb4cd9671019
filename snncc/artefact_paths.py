"""Which kind of artefact a path holds, for refusals that say what was given and which command reads it.

A Loihi bundle is one HDF5 file (``snncc emulate``, ``map``, ``report`` read it); a Jetson artefact
is a directory whose ``manifest.json`` names the format ``snncc-jetson-artefact`` (``snncc run``
runs it, ``snncc bench`` times it). Recognising them reads at most a few bytes or one small JSON
file, and imports nothing heavy.
"""

from __future__ import annotations

import json
from pathlib import Path

from snncc.errors import SnnccError

JETSON_FORMAT = "snncc-jetson-artefact"       # targets/jetson/manifest.py's FORMAT
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
HDF5_SIGNATURE_OFFSETS = (0, 512, 1024, 2048)  # where HDF5 allows its superblock (a user block before it)
MAX_MANIFEST_BYTES = 1 << 20

LOIHI_BUNDLE = "a Loihi bundle (.net, an HDF5 file)"
JETSON_ARTEFACT = "a Jetson artefact (a directory)"
READERS = {LOIHI_BUNDLE: "`snncc emulate` runs it, `snncc map` and `snncc report` read it",
           JETSON_ARTEFACT: "`snncc run` runs it, `snncc bench` times it"}


def is_jetson_artefact(path: str | Path) -> bool:
    """A directory whose manifest.json declares snncc's Jetson artefact format."""
    manifest = Path(path) / "manifest.json"
    try:
        if not manifest.is_file() or manifest.stat().st_size > MAX_MANIFEST_BYTES:
            return False
        return json.loads(manifest.read_text(encoding="utf-8")).get("format") == JETSON_FORMAT
    except (OSError, ValueError, AttributeError):
        return False


def is_loihi_bundle(path: str | Path) -> bool:
    """A regular file with HDF5's signature where HDF5 puts it (the format of every Loihi bundle)."""
    try:
        if not Path(path).is_file():
            return False
        with open(path, "rb") as fh:
            for offset in HDF5_SIGNATURE_OFFSETS:
                fh.seek(offset)
                if fh.read(len(HDF5_SIGNATURE)) == HDF5_SIGNATURE:
                    return True
    except OSError:
        return False
    return False


def artefact_kind(path: str | Path) -> str | None:
    """``LOIHI_BUNDLE``, ``JETSON_ARTEFACT`` or None."""
    if is_jetson_artefact(path):
        return JETSON_ARTEFACT
    if is_loihi_bundle(path):
        return LOIHI_BUNDLE
    return None


def wrong_path(path: str | Path, wanted: str, field: str | None = "path") -> SnnccError:
    """The refusal for ``path`` given where ``wanted`` (e.g. ``LOIHI_BUNDLE``) was expected: it does not
    exist, or it is another kind of artefact (named, with the command that reads it), or not a file."""
    p = Path(path)
    kind = artefact_kind(p)
    if kind is not None and kind != wanted:
        return SnnccError(f"is {kind}, not {wanted}: {READERS[kind]}", file=str(p), field=field)
    if not p.exists():
        return SnnccError("file does not exist" if "file" in wanted else "does not exist", file=str(p), field=field)
    if p.is_dir():
        return SnnccError(f"is a directory, not {wanted}", file=str(p), field=field)
    return SnnccError(f"is not a regular file (a device or pipe), not {wanted}", file=str(p), field=field)
