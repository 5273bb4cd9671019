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


def output_suffixes() -> dict[str, str]:
    """Target name -> the file suffix that names its artefact (``output_suffix``), for the installed targets
    that declare one. A target that fails to load is passed over: it cannot be chosen without being named."""
    found = {}
    for ep in entry_points(group=GROUP):
        try:
            declared = getattr(ep.load(), "output_suffix", None)
        except Exception:  # a broken third-party plug-in: named with --target, it reports itself
            continue
        if isinstance(declared, str) and declared:
            found[ep.name] = declared
    return dict(sorted(found.items()))


def targets_for_suffix(suffix: str) -> list[str]:
    """The installed targets whose artefact's suffix is ``suffix`` (case-blind)."""
    return [name for name, declared in output_suffixes().items() if declared.lower() == suffix.lower()]


def get_target(name: str) -> Target:
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            return ep.load()
    raise SnnccError(f"unknown target {name!r} (installed: {', '.join(available_targets()) or 'none'})", field="--target")


__all__ = ["Target", "Artefact", "Record", "TargetOptions", "IROptions", "LoihiOptions", "JetsonOptions",
           "get_target", "available_targets", "output_suffixes", "targets_for_suffix", "capability", "target_options", "OPTION_FLAGS"]
