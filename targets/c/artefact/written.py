"""A written C artefact read back: its manifest (every listed file checked against its SHA-256), its network
(``network.npz``), and the proof that its C is that network's (snn.c and snn.h regenerated, byte for byte, when
the artefact was written by this code generator: ``csource.GENERATOR``; an older one's C states the same arithmetic
in other words, and the manifest's hashes still hold it). Also the ``identify`` capability (reads the manifest
only)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from snncc.targets.kit import SnnccError
from snncc.targets.kit.artefact import ArtefactIdentity, artefact_sha256, member
from snncc.targets.c.artefact.package import ARTEFACT


@dataclass
class WrittenC:
    path: Path
    manifest: dict[str, Any]
    network: Any                      # lowering.network.CNetwork
    sha256: str

    @property
    def layout(self) -> dict[str, Any]:
        return dict(self.manifest.get("input_layout") or {})


def open_artefact(path: str | Path) -> WrittenC:
    """The artefact at ``path``, checked (module doc); one line naming the file where it is not one."""
    from snncc.targets.c.artefact import csource
    from snncc.targets.c.lowering.network import read_network

    path = Path(path)
    manifest = ARTEFACT.open(path)
    net = read_network(member(path, "network.npz").read_bytes(), source=str(path / "network.npz"))
    files = sorted(ARTEFACT.own_files(manifest))
    if manifest.get("generator") != csource.GENERATOR:
        return WrittenC(path, manifest, net, artefact_sha256(path, files)[0])
    meta = {"model": (manifest.get("source") or {}).get("file") or (manifest.get("model") or {}).get("graph_sha256")}
    for name, text in (("snn.c", csource.source(net, meta)), ("snn.h", csource.header(net, meta))):
        if member(path, name).read_bytes() != text.encode():
            raise SnnccError("is not the C of the artefact's network.npz (regenerated, it differs)",
                             file=str(path / name), field=name)
    return WrittenC(path, manifest, net, artefact_sha256(path, files)[0])


def identify_artefact(path: str | Path) -> ArtefactIdentity | None:
    found = ARTEFACT.identify(path)
    if found is None:
        return None
    manifest = ARTEFACT.manifest(path) or {}
    model = manifest.get("model")
    found.model = model if isinstance(model, dict) else None
    return found


__all__ = ["WrittenC", "open_artefact", "identify_artefact"]
