"""A command's target flags, built from the registered targets' declarations (``snncc.targets.base``).

``@with_target_flags("lower")`` adds to a typer command one option per flag the registered targets
declare for those capabilities (``snncc.targets.offered_options``): its help names the targets that
take it; a switch defaults to off and a value to None (not given), so the chosen target sees only
what the user gave. The command receives them as one mapping, ``target_options``, and passes it to
the verb unread: a target's new option needs no edit here. The flags are read from the registry
each time typer builds the command (not when this module is imported), so a target installed
later in the same process is offered too.

An option declared as a path (``option(..., path="input" | "output")``) is a path parameter of the
command like its own (``snncc.cli.paths``): declared by role, and an input is protected from every
output while the command runs; the verb receives it as text.
"""

from __future__ import annotations

import inspect
import os
import typing
from pathlib import Path
from typing import Any, Callable, Optional

import typer

PARAMETER = "target_options"


def _parameter(offer) -> inspect.Parameter:
    if offer.kind is bool:
        default = typer.Option(False, offer.flag, help=offer.help, show_default=False)
        annotation: Any = bool
    else:
        default = typer.Option(None, offer.flag, help=offer.help, show_default=False)
        annotation = Optional[Path] if offer.path else Optional[offer.kind]
    return inspect.Parameter(offer.name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=annotation)


class TargetFlagged:
    """The command, callable by typer with its own options and the targets' flags (see the module doc)."""

    def __init__(self, command: Callable[..., Any], capabilities: tuple[str, ...]) -> None:
        self.command = command
        self.capabilities = capabilities
        self.__name__ = command.__name__
        self.__qualname__ = command.__qualname__
        self.__module__ = command.__module__
        self.__doc__ = command.__doc__
        self._built: tuple[object, list[inspect.Parameter], dict[str, str]] | None = None

    def _parameters(self) -> list[inspect.Parameter]:
        """The command's parameters with the targets' flags (rebuilt when the installed targets change)."""
        return self._current()[1]

    def _current(self) -> tuple[object, list[inspect.Parameter], dict[str, str]]:
        """(installed targets, parameters, path role of each offered path option), rebuilt on a change."""
        from importlib.metadata import entry_points

        from snncc.targets import GROUP

        key = tuple(sorted((ep.name, ep.value) for ep in entry_points(group=GROUP)))
        if self._built is None or self._built[0] != key:
            self._built = (key, *self._build())
        return self._built

    def _build(self) -> tuple[list[inspect.Parameter], dict[str, str]]:
        from snncc.targets import offered_options

        hints = typing.get_type_hints(self.command)       # the command's own annotations, resolved in its module
        own = [p.replace(annotation=hints.get(p.name, p.annotation), kind=inspect.Parameter.KEYWORD_ONLY)
               for p in inspect.signature(self.command).parameters.values() if p.name != PARAMETER]
        offered = offered_options(self.capabilities)
        roles = {o.name: o.path for o in offered if o.path}
        offers = [_parameter(o) for o in offered]
        clash = {p.name for p in offers} & {p.name for p in own}
        if clash:
            raise TypeError(f"{self.__name__}: targets declare options named like the command's own: {sorted(clash)}")
        cut = next((i for i, p in enumerate(own) if p.name == "json_out"), len(own))
        return own[:cut] + offers + own[cut:], roles

    @property
    def __snncc_paths__(self) -> Any:
        """The command's path declaration with the offered path options added by role."""
        from snncc.cli.paths import PathDeclaration, declaration_of

        inner = declaration_of(self.command) or PathDeclaration()
        roles = self._current()[2]
        return PathDeclaration(inner.inputs + tuple(n for n, r in roles.items() if r == "input"),
                               inner.outputs + tuple(n for n, r in roles.items() if r == "output"),
                               inner.study_storage)

    @property
    def __signature__(self) -> inspect.Signature:
        return inspect.Signature(self._parameters())

    @property
    def __annotations__(self) -> dict[str, Any]:
        return {p.name: p.annotation for p in self._parameters()}

    def __call__(self, **given: Any) -> Any:
        from snncc.atomic import protecting

        own = set(inspect.signature(self.command).parameters)
        options = {name: given.pop(name) for name in list(given) if name not in own}
        roles = self._current()[2]
        options = {k: os.fspath(v) if roles.get(k) and v is not None else v for k, v in options.items()}
        with protecting([v for k, v in options.items() if roles.get(k) == "input" and v is not None]):
            return self.command(**given, **{PARAMETER: options})


def with_target_flags(*capabilities: str) -> Callable[[Callable[..., Any]], TargetFlagged]:
    """Give the decorated command (which takes ``target_options``) the registered targets' flags for
    ``capabilities``, placed before its ``--json`` option."""
    def decorate(command: Callable[..., Any]) -> TargetFlagged:
        return TargetFlagged(command, capabilities)

    return decorate
