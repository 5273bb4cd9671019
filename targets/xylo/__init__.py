"""SynSense Xylo target (Xylo Audio 2 SYNS61201, Xylo IMU SYNS63300, Xylo Audio 3 SYNS65302).

The folder shows the stages: ``capabilities`` (the registered target, light), ``options`` (its option record
and constants), ``chip`` (each chip's limits and the v2 core's arithmetic as data), ``spec`` (the network
record ``XyloSpec``: the keyword arguments of Rockpool's ``XyloSim.from_specification``, and its .npz file),
``feed`` (how the model's time maps to the chip's), and the sub-packages ``lowering``, ``artefact``,
``emulation``, ``checks``, ``estimate`` and ``finetune``. See docs/xylo.md. The names below resolve on first
use, so importing the package imports nothing heavy.
"""

from __future__ import annotations

import importlib

_HOMES = {
    "CHIPS": "chip", "CORE": "chip", "XyloChip": "chip", "get_chip": "chip",
    "XyloSpec": "spec", "load_npz": "spec",
    "emulate": "emulation.emulator", "reference_run": "emulation.emulator", "XyloResult": "emulation.emulator",
    "XyloOptions": "options", "XyloStudyKnobs": "options",
}

__all__ = sorted(_HOMES)


def __getattr__(name: str):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'snncc.targets.xylo' has no attribute {name!r}")
    return getattr(importlib.import_module(f"snncc.targets.xylo.{home}"), name)
