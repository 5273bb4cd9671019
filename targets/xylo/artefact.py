"""The Xylo artefact: a directory that a user with a board, or XyloSim, can take as it is.

    spec.npz        the network as the keyword arguments of Rockpool's ``XyloSim.from_specification``
                    (``XyloSpec.npz_arrays``: integer dtypes, no pickles; aliases as an int32 table
                    padded with -1; dt a 0-d float64)
    manifest.json   chip, dt, aliases, how to feed the chip (input_pad, output_lag), the quantization
                    record, SHA-256 of every file, the source model, the versions it was checked with
    README.md       what the files are, how to run them in XyloSim, what was and was not exercised
    run_on_board.py a script for Rockpool + samna (NOT exercised here: no board and no samna)

Written atomically (``snncc.atomic.atomic_dir``): an existing directory is replaced only when it is an
earlier snncc Xylo artefact holding nothing else. Identical inputs give byte-identical files (the
zip members of spec.npz carry a fixed date).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snncc.atomic import atomic_dir, foreign_entries

FORMAT = "snncc-xylo-artefact"
FORMAT_VERSION = 1
SPEC = "spec.npz"
MANIFEST = "manifest.json"
README = "README.md"
BOARD_SCRIPT = "run_on_board.py"
FILES = (SPEC, MANIFEST, README, BOARD_SCRIPT)
XYLOSIM_VERSION = "0.1.3"       # the oracle snncc's emulator is tested against (tests/xylo, in CI)
ZIP_DATE = (1980, 1, 1, 0, 0, 0)


def npz_bytes(arrays: dict) -> bytes:
    """``arrays`` as .npz bytes (deflated .npy members, fixed member dates: byte-identical for equal arrays)."""
    import numpy as np

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=6) as zf:
        for name, value in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            member = io.BytesIO()
            np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)
            zf.writestr(info, member.getvalue())
    return buf.getvalue()


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def replace_refusal(directory: str | os.PathLike) -> str | None:
    """None if ``directory`` is an earlier snncc Xylo artefact holding only its own regular files; else why not."""
    directory = Path(directory)
    try:
        manifest = json.loads((directory / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return f"it has no readable {MANIFEST} of an snncc Xylo artefact"
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        return f"its {MANIFEST} is not an snncc Xylo manifest"
    return foreign_entries(directory, FILES)


@dataclass
class XyloArtefact:
    """A lowered model's files (bytes, in write order), its manifest and the notes for the user."""

    files: dict[str, bytes]
    manifest: dict[str, Any]
    notes: list[str] = field(default_factory=list)

    def write(self, path: str | os.PathLike) -> None:
        with atomic_dir(Path(path), replaceable=replace_refusal) as tmp:
            for name, data in self.files.items():
                (tmp / name).write_bytes(data)
            os.chmod(tmp / BOARD_SCRIPT, 0o755)

    def summary(self) -> dict[str, Any]:
        m = self.manifest
        q = m["quantization"]
        return {"format": f"Xylo artefact directory ({', '.join(FILES)})", "chip": m["chip"], "dt": m["dt"],
                "network": m["network"], "feed": m["feed"], "rule": q["rule"], "candidates": q["candidates"],
                "changes": q["changes"], "real_time": m["real_time"], "validation": m["validation"],
                "files": {n: {"bytes": len(d), "sha256": sha256(d)} for n, d in self.files.items()},
                "notes": list(self.notes)}

    def render_text(self, console) -> None:
        s = self.summary()
        net, chip = s["network"], s["chip"]
        console.print(f"{chip['name']} ({chip['part_number']}): {net['inputs']} inputs -> {net['hidden']} hidden -> "
                      f"{net['outputs']} outputs, {net['synapses']} synapses; rule {s['rule']}", markup=False)
        for name, agr in s["candidates"].items():
            console.print(f"  candidate {name}: agreement {agr['agreement']:.3f} [{agr['low']:.3f}, {agr['high']:.3f}] "
                          f"over {agr['counted']} clear-winner calibration samples", markup=False)
        for line in s["changes"]:
            console.print(f"  change: {line}", markup=False)
        rt = s["real_time"]
        console.print(f"  real time: {'yes' if rt['real_time'] else 'NO'}, at most {rt['cycles_worst']:,.0f} core cycles "
                      f"per step, margin {rt['margin']:.1f}x against dt (ESTIMATE)", markup=False)
        v = s["validation"]
        console.print(f"  validation: {v['spec_file']}; {v['emulator']}", markup=False)
        for note in s["notes"]:
            console.print(f"  note: {note}", markup=False, soft_wrap=True)
