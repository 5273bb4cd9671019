"""Loihi 1 target: HDF5 bundle (netx layout), core map, bit-exact emulator, energy estimate.

The package's face. ``target`` (the registered target) and ``LoihiTarget`` live in
``capabilities.py`` (light: each capability imports its work on use); ``LoihiArtefact`` lives in
``artefact.py`` (its text in ``report_text.py``) and ``lower_model`` in ``compiler.py`` (lowering
orchestration: quantization, timing, core map, validation against the IR reference); they are
resolved on first use, so tools that only read, map or emulate a bundle (``bundle``, ``emulator``,
``partition``) never import the compiler's torch-based reference simulator.
"""

from __future__ import annotations

import importlib

_HOMES = {
    "target": "capabilities", "LoihiTarget": "capabilities", "LoihiArtefact": "artefact", "lower_model": "compiler",
    "attach_core_map": "compiler", "count_error": "compiler", "LoweredModel": "compiler",
    "LoihiNetwork": "network",
}

__all__ = ["target", "LoihiTarget", "LoihiArtefact", "LoihiNetwork", "lower_model"]


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'snncc.targets.loihi' has no attribute {name!r}")
    return getattr(importlib.import_module(f"snncc.targets.loihi.{home}"), name)
