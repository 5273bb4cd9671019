"""The artefact to measure: the one the user gave (``--artefact``), or the one ``snncc compile`` would write.

``check``, ``agree``, ``map`` of a model file and ``compare`` all measure a written file, never what the
compiler remembers of it. Without a given artefact, the target's ``lower`` runs with compile's options
(the same options give the same artefact and the same SHA-256) and the artefact is written into a
temporary directory that is removed when the block ends. This is the one place that does it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from snncc.ir.graph import Graph
    from snncc.progress import Progress
    from snncc.targets.base import Given, Target


def compile_options(target: Target, options: Given) -> Any:
    """``target``'s option record for ``lower`` from ``options`` (a record, returned as it is; or a mapping whose
    keys that are no field of the record, such as a check's own settings, are left out)."""
    from snncc.targets.base import OptionRecord, TargetOptions, target_options

    if isinstance(options, OptionRecord):
        return options
    kind = getattr(target, "options_type", TargetOptions)
    names = {f.name for f in dataclasses.fields(kind)}
    given = {k: v for k, v in dict(options or {}).items() if k in names}
    return target_options(target, given, "lower")


@contextlib.contextmanager
def compiled(target: Target, graph: Graph, options: Given = None, *,
             progress: Progress | None = None) -> Iterator[Path]:
    """The path of the artefact ``snncc compile`` would write for ``graph`` (``target.lower`` with ``options``),
    in a temporary directory removed when the block ends."""
    from snncc.targets.base import capability

    artefact = capability(target, "lower")(graph, compile_options(target, options), progress=progress)
    with tempfile.TemporaryDirectory(prefix="snncc-measure-") as tmp:
        path = Path(tmp) / f"artefact{getattr(target, 'output_suffix', '') or ''}"
        artefact.write(path)
        yield path


@contextlib.contextmanager
def artefact_to_measure(target: Target, graph: Graph, options: Given = None,
                        artefact: str | os.PathLike | None = None, *,
                        progress: Progress | None = None) -> Iterator[Path]:
    """``artefact`` when given (the user's file, measured as it is); else ``compiled(target, graph, options)``."""
    if artefact is not None:
        yield Path(artefact)
        return
    with compiled(target, graph, options, progress=progress) as path:
        yield path


def described(artefact: str | os.PathLike | None, path: Path) -> str:
    """How a record names the measured artefact: the user's path, or that it was compiled for the measurement
    (a temporary path would name a file that no longer exists when the user reads the record)."""
    return str(artefact) if artefact is not None else "compiled for this measurement as `snncc compile` would write it"


def recorded_options(values: Mapping[str, Any], keys: tuple[str, ...]) -> dict[str, Any]:
    """The entries of ``values`` named by ``keys`` that are set (not None): what an artefact records of the
    options it was compiled with."""
    return {k: values[k] for k in keys if values.get(k) is not None}


__all__ = ["artefact_to_measure", "compiled", "compile_options", "described", "recorded_options"]
