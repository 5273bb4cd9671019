"""Loading ``.pt`` files safely: ``torch.load(weights_only=True, map_location="cpu")`` only.

A pickle that needs arbitrary globals is refused, never executed. Every failure becomes one
SnnccError naming the file and what it is not.
"""

from __future__ import annotations

import warnings
import zipfile
from pathlib import Path
from typing import Any

import torch

from snncc.errors import SnnccError


def _hdf5_kind(path: Path) -> str | None:
    """What an HDF5 file given as a model is: a Loihi bundle (netx's /layer group), a NIR graph
    under another suffix (/node), another HDF5 file; None if it is not HDF5. Reads only the root's names."""
    import h5py

    if not h5py.is_hdf5(str(path)):
        return None
    try:
        with h5py.File(path, "r") as f:
            names = set(f.keys())
    except (OSError, ValueError):
        return "a damaged HDF5 file, not a model file"
    from snncc.artefacts import artefact_note

    note = artefact_note(path)      # an installed target's artefact (a Loihi bundle is HDF5)
    if note is not None:
        return f"{note}; it is not a model file"
    if "node" in names:
        return "is a NIR graph (an HDF5 file) under another suffix: name it .nir"
    return "an HDF5 file that is neither a model file, a NIR graph nor an artefact an installed target recognises"


def _classify(path: Path) -> str:
    hdf5 = _hdf5_kind(path)
    if hdf5 is not None:
        return hdf5
    head = path.read_bytes()[:4]
    if head.startswith(b"PK"):
        try:
            with zipfile.ZipFile(path) as zf:
                names = zf.namelist()
        except (zipfile.BadZipFile, ValueError, OSError, EOFError):   # ValueError: a member name flagged UTF-8 but not
            return "a truncated or damaged zip archive, not a readable torch file"
        if not any(n.endswith("data.pkl") for n in names):
            return "a zip archive that is not a torch file (no data.pkl inside)"
        return "a damaged torch archive"
    if head[:1] == b"\x80":
        return "a pickle that is not a torch tensor file"
    return "not a torch model file (unrecognised bytes)"


REFUSED = ("refused: the file's pickle needs arbitrary Python objects (loaded with weights_only=True); "
           "snncc never executes code from a model file")


def load_torch_file(path: str | Path) -> Any:
    """The object stored in ``path``, loaded with weights_only=True onto the CPU."""
    path = Path(path)
    if not path.exists():
        raise SnnccError("file does not exist", file=str(path), field="path")
    if not path.is_file():
        raise SnnccError("is not a regular file (a directory, device or pipe)", file=str(path), field="path")
    if path.stat().st_size == 0:
        raise SnnccError("file is empty", file=str(path), field="contents")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # torch's note on pickle protocols
            return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as ex:  # torch raises many types for bad bytes; all become one line
        msg = str(ex)
        if "GLOBAL" in msg or "Unsupported global" in msg or "Unsupported class" in msg:
            raise SnnccError(REFUSED, file=str(path), field="pickle") from None
        raise SnnccError(_classify(path), file=str(path), field="contents") from None
