"""Is a path a Loihi bundle, and from which model? (the Loihi target's ``identify``)

A bundle is one HDF5 file with a ``/layer`` group (snncc's, lava-dl netx's or SLAYER v1's layout; a
bundle missing its ``/simulation`` group is still recognised, so the reader can say what is missing). snncc's bundles record the model file they were compiled from in
``/snncc/source_sha256`` and ``/snncc/metadata`` (``source_file``), and the graph compiled in ``/snncc/model``
(``kit.artefact.model_record``: returned as ``identity.model``; None in a bundle of an older snncc); other
writers' do not. Nothing else is read here: the full reader (``read.read_bundle``) validates the bundle when it
runs.
"""

from __future__ import annotations

import json
from pathlib import Path

from snncc.targets.kit.artefact import ArtefactIdentity


def identify_bundle(path: str | Path) -> ArtefactIdentity | None:
    """The bundle's identity, or None when ``path`` is no HDF5 file with a /layer group."""
    import h5py

    from snncc.targets.loihi.bundle.layout import SNNCC_GROUP
    from snncc.targets.loihi.bundle.read import _text

    path = Path(path)
    if not path.is_file() or not h5py.is_hdf5(str(path)):
        return None
    try:
        with h5py.File(str(path), "r") as f:
            if not isinstance(f.get("layer"), h5py.Group):
                return None
            sha, source, model = None, None, None
            group = f.get(SNNCC_GROUP)
            if isinstance(group, h5py.Group):
                if "model" in group:
                    try:
                        found = json.loads(_text(group["model"]))
                    except (ValueError, AttributeError):
                        found = None
                    model = found if isinstance(found, dict) else None
                if "source_sha256" in group:
                    sha = _text(group["source_sha256"]) or None
                if "metadata" in group:
                    try:
                        source = json.loads(_text(group["metadata"])).get("source_file") or None
                    except (ValueError, AttributeError):
                        source = None
            writer = "snncc" if isinstance(group, h5py.Group) else "another writer (netx / SLAYER layout)"
    except (OSError, RuntimeError, ValueError, KeyError):
        return None
    return ArtefactIdentity(target="loihi", path=str(path), files=[], source_sha256=sha, source_file=source,
                            description=f"Loihi bundle (HDF5, lava-dl netx layout), written by {writer}", model=model)
