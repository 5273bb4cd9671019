"""Targets, found through the ``snncc.targets`` entry-point group (third parties plug in there).

A target offers ``lower(graph, options) -> Artefact``; an artefact offers ``write(path)``
(atomic), ``validate(graph, inputs) -> dict`` against the IR reference, and ``summary()``.
"""

from __future__ import annotations

from importlib.metadata import entry_points

from snncc.errors import SnnccError
from snncc.targets.base import Artefact, Target

GROUP = "snncc.targets"


def available_targets() -> list[str]:
    return sorted({ep.name for ep in entry_points(group=GROUP)})


def get_target(name: str) -> Target:
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            return ep.load()
    raise SnnccError(f"unknown target {name!r} (installed: {', '.join(available_targets()) or 'none'})", field="--target")


__all__ = ["Target", "Artefact", "get_target", "available_targets"]
