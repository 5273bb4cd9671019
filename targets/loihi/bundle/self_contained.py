"""An HDF5 input must hold its own data: no link or dataset may lead to another file.

HDF5 lets a file point elsewhere: an external link (``/layer/0/weight -> other.h5:/x``), a soft
link (a path inside the file, possibly to an external link), a dataset whose raw data is stored in
other files (``external`` storage) or assembled from them (a virtual dataset). Reading such a
"bundle" would read the other file. snncc's inputs (Loihi bundles, NIR graphs) hold every value
directly in hard-linked groups and datasets; anything else is refused before a value is read.

INTERIM COPY of ``snncc/hdf5_links.py`` (the NIR frontend uses that one): a target imports from snncc only the
interface, the kit and the IR, and the kit does not offer this check yet. When the kit does (asked of the lead),
this module goes and ``read.py`` imports the kit's.
"""

from __future__ import annotations

from snncc.targets.kit import SnnccError

MAX_OBJECTS = 1_000_000     # a walk over more links than this is refused (hard-link cycles, bloat)


def check_self_contained(f, path: str) -> None:
    """Raise SnnccError (file ``path``, field the HDF5 path) unless every link in the open h5py file
    ``f`` is a hard link and no dataset keeps its data outside the file. A file whose structure
    h5py cannot walk (damaged object headers, say) is refused as damaged."""
    try:
        _walk(f, path)
    except SnnccError:
        raise
    except (KeyError, OSError, RuntimeError, ValueError, TypeError) as err:
        raise SnnccError(f"damaged HDF5 structure ({type(err).__name__}: {err})", file=path, field="format") from None


def _walk(f, path: str) -> None:
    import h5py

    seen: set = set()
    todo = [f]
    count = 0
    while todo:
        group = todo.pop()
        for name in group:
            count += 1
            if count > MAX_OBJECTS:
                raise SnnccError(f"holds more than {MAX_OBJECTS:,} links", file=path, field=group.name)
            where = f"{group.name.rstrip('/')}/{name}"
            link = group.get(name, getlink=True)
            if isinstance(link, h5py.ExternalLink):
                raise SnnccError(f"is an external link to {link.filename!r}:{link.path}; the file must hold its own "
                                 "data (no links to other files)", file=path, field=where)
            if not isinstance(link, h5py.HardLink):
                target = getattr(link, "path", None)
                raise SnnccError(f"is a {type(link).__name__} ({target!r}); the file must hold its data directly "
                                 "(hard links only)", file=path, field=where)
            obj = group[name]
            if isinstance(obj, h5py.Dataset):
                if obj.is_virtual:
                    raise SnnccError("is a virtual dataset (its data lie in other files); the file must hold its "
                                     "own data", file=path, field=where)
                if obj.external:
                    raise SnnccError(f"keeps its data in an external file ({obj.external[0][0]!r}); the file must "
                                     "hold its own data", file=path, field=where)
            elif isinstance(obj, h5py.Group):
                key = hash(obj.id)
                if key not in seen:
                    seen.add(key)
                    todo.append(obj)
