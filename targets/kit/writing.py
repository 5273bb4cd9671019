"""Writing an artefact so that no file is ever lost or half-written (``snncc.atomic``'s rules).

    atomic_path(dest)                     a temporary sibling renamed onto ``dest`` when the block succeeds
    atomic_dir(dest, replaceable)         the same for a directory; an existing one replaced only when
                                          ``replaceable(dest)`` returns None (an earlier artefact of ours)
    write_bytes_atomic / write_text_atomic / write_npz_atomic
    foreign_entries(directory, ours)      why a directory holding other files than ``ours`` is not ours
    record_input(path)                    a file read from inside an input directory: no output may replace it
    npz_bytes(arrays)                     .npz bytes that are identical for identical arrays (fixed member dates)

An output is refused before anything is written when it resolves to one of the command's inputs or
a directory holding one, or lies inside an input directory artefact (``snncc.atomic.check_destination``).
"""

from __future__ import annotations

import io
import zipfile

from snncc.atomic import (
    atomic_dir, atomic_path, foreign_entries, preflight, record_input, write_bytes_atomic, write_npz_atomic,
    write_text_atomic,
)

ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def npz_bytes(arrays: dict, compresslevel: int = 6) -> bytes:
    """``arrays`` as .npz bytes: deflated .npy members without pickles, each member dated ``ZIP_DATE`` so equal
    arrays give byte-identical files (``numpy.load(allow_pickle=False)`` reads them)."""
    import numpy as np

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=compresslevel) as zf:
        for name, value in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            member = io.BytesIO()
            np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)
            zf.writestr(info, member.getvalue())
    return buf.getvalue()


__all__ = ["atomic_dir", "atomic_path", "foreign_entries", "preflight", "record_input", "write_bytes_atomic",
           "write_npz_atomic",
           "write_text_atomic", "npz_bytes", "ZIP_DATE"]
