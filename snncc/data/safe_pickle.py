"""Reading the published Braille pickles without running code from them.

A pickle names the functions that rebuild its objects, and a plain ``pickle.load`` (or
``pandas.read_pickle``) calls whatever it names: a file from the internet can run any code. The
published files only need lists, dicts, numpy arrays and pandas DataFrames, so the unpickler
here resolves only the exact names those layouts use (numpy's array reconstruction, pandas'
DataFrame/Index/BlockManager reconstruction, across numpy 1/2 and pandas 1-3 module paths, with
pandas' own renames for files written by older pandas) and refuses any other name *before* it is
called.
"""

from __future__ import annotations

import io
import pickle
from pathlib import Path
from typing import Any

from snncc.atomic import record_input
from snncc.errors import SnnccError
from snncc.limits import check_memory

_NUMPY = {
    (mod, name)
    for mod in ("numpy.core.multiarray", "numpy._core.multiarray")
    for name in ("_reconstruct", "scalar")
} | {(mod, "_frombuffer") for mod in ("numpy.core.numeric", "numpy._core.numeric")} | {
    ("numpy", "ndarray"), ("numpy", "dtype"),
}
_BUILTINS = {("builtins", "slice"), ("_codecs", "encode"), ("copyreg", "_reconstructor"), ("builtins", "object")}
_PANDAS = {
    ("pandas", "DataFrame"), ("pandas", "Series"), ("pandas", "Index"), ("pandas", "RangeIndex"),
    ("pandas", "StringDtype"), ("pandas.arrays", "StringArray"),
    ("pandas.core.frame", "DataFrame"), ("pandas.core.series", "Series"),
    ("pandas.core.indexes.base", "Index"), ("pandas.core.indexes.base", "_new_Index"),
    ("pandas.core.indexes.range", "RangeIndex"), ("pandas.core.indexes.numeric", "Int64Index"),
    ("pandas.core.internals.managers", "BlockManager"), ("pandas.core.internals.managers", "SingleBlockManager"),
    ("pandas.core.internals.blocks", "new_block"), ("pandas.core.internals.blocks", "Block"),
    ("pandas.core.internals.blocks", "ObjectBlock"), ("pandas.core.internals.blocks", "NumpyBlock"),
    ("pandas.core.internals.blocks", "IntBlock"), ("pandas.core.internals.blocks", "FloatBlock"),
    ("pandas._libs.internals", "_unpickle_block"), ("pandas._libs.arrays", "__pyx_unpickle_NDArrayBacked"),
    ("pandas.core.arrays.string_", "StringArray"), ("pandas.core.arrays.string_", "StringDtype"),
}
ALLOWED: frozenset[tuple[str, str]] = frozenset(_NUMPY | _BUILTINS | _PANDAS)


def _base_unpickler() -> tuple[type, dict]:
    """pandas' compatibility unpickler (renames of older pandas' classes) when it exists."""
    try:
        from pandas.compat import pickle_compat

        return pickle_compat.Unpickler, dict(getattr(pickle_compat, "_class_locations_map", {}))
    except (ImportError, AttributeError):
        return pickle.Unpickler, {}


def restricted_loads(data: bytes, source: str = "<pickle>") -> Any:
    """Unpickle ``data``, resolving only the names in :data:`ALLOWED` (one-line error otherwise)."""
    base, renames = _base_unpickler()

    class RestrictedUnpickler(base):  # type: ignore[misc, valid-type]
        def find_class(self, module: str, name: str) -> Any:
            if (module, name) not in ALLOWED and tuple(renames.get((module, name), ())) not in ALLOWED:
                raise SnnccError(f"refers to {module}.{name}, which the published Braille layouts never use; "
                                 "refused without running it (only lists, dicts, numpy arrays and pandas "
                                 "DataFrames are read)", file=source, field="pickle")
            return super().find_class(module, name)

    try:
        return RestrictedUnpickler(io.BytesIO(data)).load()
    except SnnccError:
        raise
    except Exception as ex:  # truncated, corrupt or not a pickle: a bad file, never a traceback
        raise SnnccError(f"not a readable pickle of the published Braille format ({type(ex).__name__})",
                         file=source, field="pickle") from None


def load_published_pickle(path: str | Path) -> Any:
    """The object a published Braille ``.pkl`` holds, read without executing anything from it."""
    path = Path(path)
    if not path.exists():
        raise SnnccError("file not found", file=str(path), field="path")
    if path.is_dir():
        raise SnnccError("expected a .pkl file, got a directory", file=str(path), field="path")
    if not path.is_file():
        raise SnnccError("is not a regular file (a device or pipe); give a .pkl file", file=str(path), field="path")
    check_memory(2 * path.stat().st_size, "reading this pickle", file=str(path), field="size")
    record_input(path)   # no output of this command may replace it (it may sit in an input directory)
    return restricted_loads(path.read_bytes(), str(path))
