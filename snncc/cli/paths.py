"""Which parameters of a command name files it reads (inputs) and which name what it writes (outputs).

Every command with a path parameter declares each one (``@declares_paths(inputs=..., outputs=...)``,
placed directly above the command's ``def``); ``tests/cli/test_path_declarations.py`` fails for a
registered command with an undeclared path parameter. While the command runs, its inputs are
protected (``snncc.atomic.protecting``): no output may be written over a file that resolves (after
symlinks) to an input, and no directory output may replace a directory holding one. Outputs are
never protected, so a command re-run over its own earlier outputs simply replaces them.

``study_storage`` names the (storage URL, ``--dir``) parameter pair of the ``hpo`` commands: the
study's SQLite database (the URL's file, or ``DIR/hpo.sqlite3`` without a URL) is an input.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from typing import Any, Callable, Iterable

ATTRIBUTE = "__snncc_paths__"


@dataclass(frozen=True)
class PathDeclaration:
    """A command's path parameters by role (parameter names as in the command's signature)."""

    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    study_storage: tuple[str, str] | None = None

    def names(self) -> set[str]:
        return {*self.inputs, *self.outputs, *(self.study_storage or ())}

    def input_paths(self, values: dict[str, Any]) -> list[str]:
        """The paths the command reads, from its parsed parameter ``values``."""
        found = [path for name in self.inputs for path in _paths(values.get(name))]
        if self.study_storage is not None:
            url_name, dir_name = self.study_storage
            database = _study_database(values.get(url_name), values.get(dir_name))
            if database is not None:
                found.append(database)
        return found


def _paths(value: Any) -> Iterable[str]:
    if value is None:
        return []
    if isinstance(value, (list, tuple)):
        return [os.fspath(v) for v in value if v is not None]
    return [os.fspath(value)]


def _study_database(url: str | None, workdir: Any) -> str | None:
    """The SQLite file a study storage lives in (None: another database server, or no file).
    Called only when an ``hpo`` command runs (``snncc.hpo`` imports the search's libraries)."""
    from pathlib import Path

    if url is None:
        return None if workdir is None else os.fspath(Path(workdir) / "hpo.sqlite3")
    from snncc.hpo.storage import sqlite_file

    database = sqlite_file(url)
    return None if database is None else os.fspath(database)


def declares_paths(*, inputs: tuple[str, ...] = (), outputs: tuple[str, ...] = (),
                   study_storage: tuple[str, str] | None = None) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Declare the command's input and output path parameters; run it with its inputs protected."""
    declaration = PathDeclaration(tuple(inputs), tuple(outputs), study_storage)

    def decorate(command: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(command)
        def protected(**values: Any) -> Any:
            from snncc.atomic import protecting

            with protecting(declaration.input_paths(values)):
                return command(**values)

        setattr(protected, ATTRIBUTE, declaration)
        return protected

    return decorate


def declaration_of(callback: Any) -> PathDeclaration | None:
    """The declaration of a registered command's callback (through typer's and the target flags' wrappers)."""
    seen: set[int] = set()
    while callback is not None and id(callback) not in seen:
        seen.add(id(callback))
        found = getattr(callback, ATTRIBUTE, None)
        if isinstance(found, PathDeclaration):
            return found
        callback = getattr(callback, "__wrapped__", None) or getattr(callback, "command", None)
    return None
