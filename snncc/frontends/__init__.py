"""Frontends: every supported model file becomes a validated IR graph through ``load_model``.

Dispatch is by file suffix to a loader ``(path, LoadOptions) -> Graph``; ``.pt``-like files are
then told apart by content (snncc checkpoint or SpyTorch weight list). Loaders are imported
lazily and more can be registered (``register_frontend``) without touching this module.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any, Callable

from snncc.atomic import file_sha256
from snncc.errors import SnnccError
from snncc.frontends.load_options import OPTION_USE, LoadOptions, refuse_options  # noqa: F401  (re-exported)
from snncc.ir.graph import Graph
from snncc.ir.validate import validate

Loader = Callable[[Path, LoadOptions], Graph]

# suffix -> "module:function" (imported on first use) or a callable
_LOADERS: dict[str, str | Loader] = {
    ".snnir": "snncc.frontends.ir_file:load",
    ".nir": "snncc.frontends.nir:load",
    ".pt": "snncc.frontends.torch_models:load",
    ".pth": "snncc.frontends.torch_models:load",
    ".ckpt": "snncc.frontends.torch_models:load",
}


def register_frontend(suffix: str, loader: str | Loader) -> None:
    """Add or replace the loader for files ending in ``suffix``."""
    _LOADERS[suffix.lower()] = loader


def _resolve(spec: str | Loader, suffix: str, path: Path) -> Loader:
    if callable(spec):
        return spec
    module_name, func = spec.split(":")
    from snncc.interrupts import sigint_deferred

    try:
        # a loader imports its library (torch for .pt files): torch's C++ start-up (pybind11) aborts the process
        # ("terminate called ... KeyboardInterrupt") when a Ctrl-C lands inside it, so the Ctrl-C waits for the
        # import to end and is raised then (the CLI says "interrupted", exit 130)
        with sigint_deferred():
            module = importlib.import_module(module_name)
    except ModuleNotFoundError as ex:
        if ex.name == module_name:
            raise SnnccError(f"no frontend for {suffix} files is installed in this snncc", file=str(path), field="format") from None
        raise
    return getattr(module, func)


def load_model(path: str | Path, options: LoadOptions | None = None) -> Graph:
    """Load ``path`` with the frontend for its format, validate the graph and stamp its source hash."""
    path = Path(path)
    options = options or LoadOptions()
    if not path.is_file():
        from snncc.artefacts import not_a_model_file

        raise not_a_model_file(path)
    suffix = path.suffix.lower()
    spec = _LOADERS.get(suffix, _LOADERS[".pt"])
    try:
        graph = _resolve(spec, suffix, path)(path, options)
        validate(graph)
    except SnnccError as err:
        raise err.with_file(str(path)) from None
    check_loaded(graph, str(path))
    graph.metadata.setdefault("source_file", path.name)
    graph.metadata["source_sha256"] = file_sha256(path)
    return graph


def import_notes(graph: Graph) -> list[str]:
    """What the frontend assumed in loading ``graph`` (dt inferred, reset chosen, ...), one line each,
    prefixed with the source file's name: ``<file>: <note>``."""
    source = graph.metadata.get("source_file", "")
    return [f"{source + ': ' if source else ''}{note}" for note in graph.metadata.get("import_notes") or []]


def check_loaded(graph: Graph, source: str) -> None:
    """Rules every loader shares after validation: the sample length is bounded, all-zero weights noted.

    An all-zero network is legal (it never spikes from its input), so it is accepted by every
    loader with a note rather than refused by some and not others.
    """
    from snncc.ir.nodes import LSTM, Dense
    from snncc.limits import check_time_steps

    length = graph.metadata.get("recording_length_s")
    if isinstance(length, (int, float)) and not isinstance(length, bool) and length > 0:
        check_time_steps(float(length) / graph.dt, f"dt = {graph.dt:g} s over the {length:g} s recording",
                         file=source, field="dt")
    weights = [op.weight for _, op in graph.items() if isinstance(op, Dense)]
    weights += [w for _, op in graph.items() if isinstance(op, LSTM) for w in (op.weight_ih, op.weight_hh)]
    if weights and not any(w.any() for w in weights):
        note = ("all weights are zero: the network is legal but its output never depends on its input "
                "(a Loihi bundle stores it with the smallest weight scale)")
        notes = graph.metadata.setdefault("import_notes", [])
        if note not in notes:
            notes.append(note)


def graph_from_object(obj: Any, source: str = "<object>", options: LoadOptions | None = None) -> Graph:
    """An IR graph from an in-memory model: a zoo module, a checkpoint dict or a weight list."""
    from snncc.frontends import torch_models

    return validate(torch_models.from_object(obj, Path(source), options or LoadOptions()))
