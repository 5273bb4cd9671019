"""Loihi 1 target: HDF5 bundle (netx layout), core map, bit-exact emulator, energy estimate.

The package's face. ``target`` (the registered target) and ``LoihiTarget`` live in
``capabilities.py`` (light: each capability imports its work on use). The parts, one folder each:

    chip.py         Loihi 1's number formats and limits, stated once (imports nothing)
    network.py      LoihiNetwork: the network as plain data (what bundle, emulator and mapper share)
    lowering/       IR graph -> LoihiNetwork -> LoihiArtefact (timing, quantization, registers)
    mapping/        the network placed on cores under every per-core limit (relays for wide fan-in)
    emulation/      the bit-exact emulator and ``snncc emulate``'s work
    bundle/         the HDF5 bundle (netx layout) read, written and checked
    estimate/       ESTIMATE of energy and delay per sample; a search trial's figures (``hardware``)
    checks/         comparisons with a reference: exactness (compile), accuracy (labels), agreement
    arithmetic/     the quantization in torch, straight-through (``arithmetic``: training through it)

Names below are resolved on first use, so tools that only read, map or emulate a bundle never
import the compiler's torch-based reference simulator.
"""

from __future__ import annotations

import importlib

_HOMES = {
    "target": "capabilities", "LoihiTarget": "capabilities", "LoihiArtefact": "lowering.artefact",
    "lower_model": "lowering.lower", "attach_core_map": "lowering.lower", "count_error": "lowering.lower",
    "LoweredModel": "lowering.lower", "LoihiNetwork": "network",
}

__all__ = ["target", "LoihiTarget", "LoihiArtefact", "LoihiNetwork", "lower_model"]


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'snncc.targets.loihi' has no attribute {name!r}")
    return getattr(importlib.import_module(f"snncc.targets.loihi.{home}"), name)
