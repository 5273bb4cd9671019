"""``snncc map``: place a written artefact (or a model file, compiled first) on its target's cores or chip, and report it."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError, one_line

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.targets.base import CoreMap


@dataclass
class MapRecord:
    source: str
    core_map: CoreMap        # the target's map (to_dict, render_text, plot)
    plot: str | None = None

    def as_dict(self) -> dict[str, object]:
        return {"source": self.source, **self.core_map.to_dict()}

    def render_text(self, console: Console) -> None:
        self.core_map.render_text(console)
        if self.plot is not None:
            console.print(f"wrote {one_line(self.plot)}", markup=False)


def map_cores(source: str | Path, *, target: str | None = None, plot: str | Path | None = None,
              params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
              **options: object) -> MapRecord:
    """``map_source`` with the target's compile options as keywords (``scale="global"``, ...)."""
    return map_source(source, target=target, plot=plot, params=params, dt=dt, reset=reset, options=options)


def map_source(source: str | Path, *, target: str | None = None, plot: str | Path | None = None,
               params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
               options: Mapping[str, object] | None = None) -> MapRecord:
    """The core map (or the chip usage) of ``source``: a written artefact, mapped as it is, or a model file,
    compiled first exactly as ``snncc compile`` would (the model options ``params``, ``dt``, ``reset`` and the
    target's compile options among ``options``; target ``target``, else ``snncc.targets.DEFAULT_TARGET``) into a
    temporary directory. ``plot`` also draws the map as a PNG (atomically; the name must end in .png)."""
    from snncc.artefacts import recognised, target_for
    from snncc.targets import DEFAULT_TARGET, capability, get_target, verb_options

    options = dict(options or {})
    path = Path(source)
    if plot is not None and Path(plot).suffix.lower() != ".png":
        raise SnnccError("the map is drawn as a PNG: name the file .png", file=str(plot), field="--plot")
    if target is not None and not recognised(path) or not recognised(path) and path.is_file():
        return _map_model(path, target or DEFAULT_TARGET, plot, params, dt, reset, options)
    tgt = target_for(path, target, "map")
    given: dict[str, object] = {"--params": params, "--dt": dt, "--reset": reset}
    given.update({"--" + k.replace("_", "-"): v for k, v in options.items() if v not in (None, False)})
    extra = next((flag for flag, value in given.items() if value is not None), None)
    if extra is not None:
        raise SnnccError("does not apply to a written artefact (compile fixed it); map the model file to choose it",
                         field=extra)
    cmap = capability(tgt, "map")(path, verb_options(tgt, {}, "map").target)
    if plot is not None:
        cmap.plot(plot)
    return MapRecord(str(source), cmap, None if plot is None else str(plot))


def _map_model(path: Path, name: str, plot: str | Path | None, params: str | Path | None, dt: float | None,
               reset: str | None, options: dict[str, object]) -> MapRecord:
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets import capability, get_target, verb_options
    from snncc.targets.kit.measured import compiled

    tgt = get_target(name)
    mapped = capability(tgt, "map", rule=f"target '{tgt.name}' has no map in this snncc")
    graph = load_model(path, LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    split = verb_options(tgt, {**options, "source": str(path)}, "lower", ("lower", "map"))
    with compiled(tgt, graph, split.target) as written:
        cmap = mapped(written, verb_options(tgt, {}, "map").target)
        notes = getattr(cmap, "notes", None)
        if isinstance(notes, list):
            notes.append(f"the model file was compiled first for {tgt.name}, exactly as snncc compile would with these "
                         "options")
        if plot is not None:
            cmap.plot(plot)
    return MapRecord(str(path), cmap, None if plot is None else str(plot))
