"""Targets, found through the ``snncc.targets`` entry-point group (third parties plug in there).

A target offers ``lower(graph, options) -> Artefact``; an artefact offers ``write(path)``
(atomic), ``validate(graph, inputs) -> dict`` against the IR reference, and ``summary()``.
"""

from __future__ import annotations

from importlib.metadata import entry_points

from snncc.errors import SnnccError
from snncc.targets.base import Artefact, Target

GROUP = "snncc.targets"


# user-facing target options (key in the options dict -> command-line flag); each target lists the
# keys it uses in ``accepts``, and a key given for a target that does not use it is refused
OPTION_FLAGS = {
    "timing": "--timing",
    "scale": "--scale",
    "allow_reset_change": "--allow-reset-change",
    "stream": "--stream",
    "jetpack": "--jetpack",
    "time_steps": "--time-steps",
}


def check_target_options(target, options: dict | None) -> None:
    """Refuse a user-given option (not None, not False) that ``target`` does not use."""
    accepts = tuple(getattr(target, "accepts", ()))
    for key, value in (options or {}).items():
        if key in OPTION_FLAGS and key not in accepts and value is not None and value is not False:
            takes = ", ".join(OPTION_FLAGS[k] for k in accepts if k in OPTION_FLAGS) or "no target options"
            raise SnnccError(f"does not apply to --target {target.name} (it takes {takes})", field=OPTION_FLAGS[key])


def available_targets() -> list[str]:
    return sorted({ep.name for ep in entry_points(group=GROUP)})


def get_target(name: str) -> Target:
    for ep in entry_points(group=GROUP):
        if ep.name == name:
            return ep.load()
    raise SnnccError(f"unknown target {name!r} (installed: {', '.join(available_targets()) or 'none'})", field="--target")


__all__ = ["Target", "Artefact", "get_target", "available_targets", "check_target_options", "OPTION_FLAGS"]
