"""Targets, found through the ``snncc.targets`` entry-point group (third parties plug in there).

The interface is ``snncc.targets.base``: a target names its typed option record
(``options_type``) and offers any of the capabilities there (``lower``, ``check``, ``agree``,
``emulate``, ``run``, ``map``, ``estimate``, ``bench``). The verbs (``snncc.api``) ask
``capability(get_target(name), verb)`` and refuse in one line when the target lacks it.

A third-party package registers its target object in its own metadata::

    [project.entry-points."snncc.targets"]
    xylo = "snncc_xylo:target"
"""

from __future__ import annotations

from importlib.metadata import entry_points

from snncc.errors import SnnccError
from snncc.targets.base import (
    OPTION_FLAGS, Artefact, IROptions, JetsonOptions, LoihiOptions, Record, Target, TargetOptions, capability,
    target_options,
)

GROUP = "snncc.targets"


def available_targets() -> list[str]:
    return sorted({ep.name for ep in entry_points(group=GROUP)})


def get_target(name: str) -> Target:
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            return ep.load()
    raise SnnccError(f"unknown target {name!r} (installed: {', '.join(available_targets()) or 'none'})", field="--target")


__all__ = ["Target", "Artefact", "Record", "TargetOptions", "IROptions", "LoihiOptions", "JetsonOptions",
           "get_target", "available_targets", "capability", "target_options", "OPTION_FLAGS"]
