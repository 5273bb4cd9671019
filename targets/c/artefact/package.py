"""The C artefact directory: its files, its manifest, and the in-memory ``CArtefact`` ``lower`` returns.

    snn.h, snn.c          the network (csource.py)
    network.npz           the same integers for the emulator (``snncc emulate``) and the checks
    main.c                example driver: reads spikes from a file, prints output counts (support.py)
    Makefile, snn.cmake   host, strict, Cortex-M4 (QEMU) and Cortex-M0 builds; a CMake library
    startup_mps2.c, mps2_an386.ld   what the Cortex-M4 build for QEMU's MPS2 AN386 board needs
    README.md             what it is and how to build, run and check it
    manifest.json         format, files and their SHA-256, source model, arithmetic, memory, the rule chosen

Written atomically through ``kit.manifest.ManifestFormat`` (an earlier C artefact is replaced only when it
holds nothing but its own files).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snncc.targets.kit.artefact import sha256_bytes
from snncc.targets.kit.manifest import MANIFEST, ManifestFormat, manifest_bytes
from snncc.targets.c.options import FORMAT, VERSION

ARTEFACT = ManifestFormat(format=FORMAT, target="c", kind="a C target artefact directory",
                          describe=lambda m: "C99 source for microcontrollers (snn.c, snn.h) with its integer network")


@dataclass
class CArtefact:
    """What ``lower`` returns: the files (name -> bytes, manifest last) and what they record."""

    files: dict[str, bytes]
    manifest: dict[str, Any]
    network: Any                                   # lowering.network.CNetwork
    notes: list[str] = field(default_factory=list)

    def write(self, path: str | Path) -> None:
        ARTEFACT.write(path, self.files)

    def summary(self) -> dict[str, Any]:
        m = self.manifest
        return {"target": "c", "format": m["format"], "sha256": m["sha256"], "rule": m["arithmetic"]["rule"],
                "selection": m["selection"], "time_steps": m["time_base"]["steps"], "memory": m["memory"],
                "part": m["part"], "populations": m["network"]["populations"],
                "projections": m["network"]["projections"], "validation": m["validation"], "notes": self.notes}

    def lines(self) -> list[str]:
        m = self.manifest
        part = m["part"]
        mem = m["memory"]
        out = [f"C artefact (snn.c, snn.h): {len(m['network']['populations'])} population(s), "
               f"{sum(p['n'] for p in m['network']['populations'])} neurons, {mem['weights']:,} weights",
               f"  rule {m['arithmetic']['rule']}: {m['selection']['reason']}"]
        for name, c in m["selection"].get("candidates", {}).items():
            share = "undefined" if c["agreement"] is None else f"{c['agreement']:.3f}"
            fits = "" if c.get("fits", True) else f", does not fit {m['part']['part']}"
            out.append(f"    {name:<14} agreement {share} ({c['agreeing']}/{c['decided']}), constant data "
                       f"{c.get('flash_data_bytes', c['weight_bytes']):,} bytes{fits}")
        out.append(f"  flash data {mem['flash_data_bytes']:,} bytes (weights {mem['flash_weights_bytes']:,}), RAM "
                   f"(state) {mem['ram_state_bytes']:,} bytes; {part['part']}: flash "
                   f"{100 * part['flash_share']:.1f} %, RAM {100 * part['ram_share']:.1f} % "
                   f"({'fits' if part['fits'] else 'DOES NOT FIT'}; code not counted here: snncc map measures it)")
        tb = m["time_base"]
        out.append(f"  {tb['steps']} steps per sample ({tb['rule']}), dt {tb['dt']} s")
        out.append(f"  checked: {m['validation']['emulator']}")
        out.append(f"  SHA-256 {m['sha256']}")
        out += [f"  note: {n}" for n in self.notes]
        return out

    def render_text(self, console: Any) -> None:
        for line in self.lines():
            console.print(line, markup=False, highlight=False, soft_wrap=True)


def network_record(net) -> dict[str, Any]:   # noqa: ANN001
    """The network as the manifest states it (no weights)."""
    pops = [{"name": p.name, "n": p.n, "frac_bits": p.frac_bits, "reset": p.reset, "refractory": p.refractory,
             "fire_test": p.fire_test, "max_spikes": p.max_spikes, "fires": p.fires,
             "threshold_units": sorted({int(v) for v in p.threshold})[:4],
             "alpha_q16": sorted({int(v) for v in p.alpha})[:4], "beta_q16": sorted({int(v) for v in p.beta})[:4],
             "voltage_bias": p.bias_v is not None, "current_bias_starts": [t.start for t in p.bias_i]}
            for p in net.populations]
    projs = [{"source": "input" if q.source < 0 else net.populations[q.source].name,
              "target": net.populations[q.target].name, "delay": q.delay, "bits": q.bits, "layout": q.layout,
              "nonzero": int((q.weights != 0).sum()), "exponents": sorted({int(e) for e in q.exponent})[:8],
              "from": q.origin} for q in net.projections]
    return {"inputs": net.inputs, "outputs": net.outputs, "output_population": net.populations[net.output].name,
            "populations": pops, "projections": projs}


def artefact_files(net, manifest: dict[str, Any],  # noqa: ANN001
                   readme: str) -> tuple[dict[str, bytes], dict[str, Any]]:
    """(files with manifest.json last, the manifest with ``files`` and ``sha256`` filled in)."""
    from snncc.targets.c.artefact import csource, support
    from snncc.targets.c.lowering.network import network_bytes
    from snncc.targets.kit.artefact import DIRECTORY_RULE

    meta = {"model": manifest["source"].get("file") or manifest["model"]["graph_sha256"]}
    files = {"snn.h": csource.header(net, meta).encode(), "snn.c": csource.source(net, meta).encode(),
             "network.npz": network_bytes(net), "main.c": support.MAIN_C.encode(),
             "Makefile": support.makefile().encode(), "snn.cmake": support.CMAKE.encode(),
             "startup_mps2.c": support.STARTUP_C.encode(), "mps2_an386.ld": support.LINKER_SCRIPT.encode(),
             "README.md": readme.encode()}
    manifest = {**manifest, "files": {name: sha256_bytes(data) for name, data in sorted(files.items())}}
    files[MANIFEST] = manifest_bytes(manifest)
    every = {name: sha256_bytes(data) for name, data in files.items()}
    listed = "".join(f"{every[name]}  {name}\n" for name in sorted(every))       # kit.artefact.artefact_sha256
    return files, {**manifest, "sha256": sha256_bytes(listed.encode()), "sha256_rule": DIRECTORY_RULE}


def base_manifest(net, graph, source: str | None, arithmetic: dict, selection: dict, time_base: dict,  # noqa: ANN001
                  memory: dict, part: dict, validation: dict, layout: dict) -> dict[str, Any]:
    from snncc.targets.c.artefact.csource import GENERATOR
    from snncc.targets.kit.artefact import model_record
    from snncc.targets.kit.manifest import source_identity

    return {"format": FORMAT, "version": VERSION, "generator": GENERATOR, "target": "c",
            "source": source_identity(graph.metadata, source), "model": model_record(graph),
            "arithmetic": arithmetic, "selection": selection, "time_base": time_base, "input_layout": layout,
            "memory": memory, "part": part, "network": network_record(net), "validation": validation,
            "api": {"reset": "void snn_reset(snn_state_t *state)",
                    "step": "void snn_step(snn_state_t *state, const uint8_t *in_spikes, uint16_t *out_counts)"}}


__all__ = ["ARTEFACT", "CArtefact", "artefact_files", "base_manifest", "network_record"]
