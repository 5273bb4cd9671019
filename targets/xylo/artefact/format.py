"""The Xylo artefact: a directory that a user with a board, or XyloSim, can take as it is.

    spec.npz        the network as the keyword arguments of Rockpool's ``XyloSim.from_specification``
                    (``XyloSpec.npz_arrays``: integer dtypes, no pickles; aliases as an int32 table
                    padded with -1; dt a 0-d float64)
    manifest.json   chip, dt, aliases, how to feed the chip (input_pad, output_lag), the quantization
                    record, SHA-256 of every file, the source model, the versions it was checked with
    README.md       what the files are, how to run them in XyloSim, what was and was not exercised
    run_on_board.py a script for Rockpool + samna (NOT exercised here: no board and no samna)

A manifest directory of the kit (``kit.manifest.ManifestFormat``, ``MANIFEST_FORMAT``): written atomically, an
existing directory replaced only when it is an earlier snncc Xylo artefact holding nothing else; read back only
after every file it lists was found a regular file inside it with the recorded SHA-256. Identical inputs give
byte-identical files (the zip members of spec.npz carry a fixed date: ``kit.writing.npz_bytes``).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from snncc.targets.kit.artefact import sha256_bytes
from snncc.targets.kit.manifest import ManifestFormat

FORMAT = "snncc-xylo-artefact"
FORMAT_VERSION = 1
SPEC = "spec.npz"
MANIFEST = "manifest.json"
README = "README.md"
BOARD_SCRIPT = "run_on_board.py"
FILES = (SPEC, MANIFEST, README, BOARD_SCRIPT)
XYLOSIM_VERSION = "0.1.3"       # the oracle snncc's emulator is tested against (tests/xylo, in CI)
KIND = "an snncc Xylo artefact directory (snncc compile --target xylo -o DIR writes one)"


def _describe(manifest: Mapping[str, Any]) -> str:
    chip = manifest.get("chip") if isinstance(manifest.get("chip"), dict) else {}
    return f"Xylo artefact ({chip.get('name', 'Xylo')}: spec.npz for XyloSim / samna)"


def _files(manifest: Mapping[str, Any]) -> Mapping[str, str | None]:
    """The artefact's files: the four it always holds, each with the SHA-256 the manifest records (None: none)."""
    listed = manifest.get("files")
    listed = listed if isinstance(listed, dict) else {}
    return {name: (listed.get(name) if isinstance(listed.get(name), str) else None) for name in FILES}


MANIFEST_FORMAT = ManifestFormat(format=FORMAT, target="xylo", kind=KIND, files=_files, describe=_describe,
                                 executable=(BOARD_SCRIPT,), manifest_name=MANIFEST)


def candidate_text(agr: Mapping[str, Any]) -> str:
    """A candidate's selection agreement (``kit.agreement``'s figures) as text; undefined over silent outputs."""
    if agr.get("share") is None:
        return f"undefined (no calibration sample with a single float winner of {agr.get('samples', 0)})"
    return (f"{agr['share']:.3f} [{agr['low']:.3f}, {agr['high']:.3f}] over {agr['decided']} decided calibration "
            "samples")


@dataclass
class XyloArtefact:
    """A lowered model's files (bytes, in write order), its manifest and the notes for the user."""

    files: dict[str, bytes]
    manifest: dict[str, Any]
    notes: list[str] = field(default_factory=list)

    def write(self, path: str | os.PathLike) -> None:
        MANIFEST_FORMAT.write(path, self.files)

    def summary(self) -> dict[str, Any]:
        m = self.manifest
        q = m["quantization"]
        return {"format": f"Xylo artefact directory ({', '.join(FILES)})", "chip": m["chip"], "dt": m["dt"],
                "network": m["network"], "feed": m["feed"], "rule": q["rule"], "candidates": q["candidates"],
                "changes": q["changes"], "real_time": m["real_time"], "validation": m["validation"],
                "files": {n: {"bytes": len(d), "sha256": sha256_bytes(d)} for n, d in self.files.items()},
                "notes": list(self.notes)}

    def render_text(self, console) -> None:
        s = self.summary()
        net, chip = s["network"], s["chip"]
        console.print(f"{chip['name']} ({chip['part_number']}): {net['inputs']} inputs -> {net['hidden']} hidden -> "
                      f"{net['outputs']} outputs, {net['synapses']} synapses; rule {s['rule']}", markup=False)
        for name, agr in s["candidates"].items():
            console.print(f"  candidate {name}: agreement {candidate_text(agr)}", markup=False)
        for line in s["changes"]:
            console.print(f"  change: {line}", markup=False)
        rt = s["real_time"]
        if "cycles_worst" in rt:
            from snncc.targets.xylo.estimate.real_time import verdict

            console.print(f"  real time {verdict(rt, 'the calibration inputs')}", markup=False, soft_wrap=True)
        else:
            console.print(f"  real time: {rt.get('note', 'not estimated')}", markup=False, soft_wrap=True)
        v = s["validation"]
        console.print(f"  validation: {v['spec_file']}; {v['emulator']}", markup=False)
        for note in s["notes"]:
            console.print(f"  note: {note}", markup=False, soft_wrap=True)
