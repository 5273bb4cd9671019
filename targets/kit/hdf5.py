"""An HDF5 artefact holds its own data (the one implementation is ``snncc.hdf5_links``): ``check_self_contained(f,
path)`` refuses, in one line, an external or soft link, external storage or a virtual dataset before a value is read
through it."""

from __future__ import annotations

from snncc.hdf5_links import MAX_OBJECTS, check_self_contained

__all__ = ["check_self_contained", "MAX_OBJECTS"]
