"""``snncc map``: place a bundle (or a model, lowered first) on the target's cores and report the core map."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import one_line

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
              **options: object) -> MapRecord:
    """The core map of ``source``; ``plot`` also draws utilisation per core as a PNG (atomically).
    ``options``: the target's for ``map`` (Loihi: ``timing``, ``scale``: they apply only when ``source``
    is a model file, lowered first)."""
    from snncc.artefacts import target_for
    from snncc.targets import capability, verb_options

    tgt = target_for(source, target, "map")
    mapped = capability(tgt, "map")
    cmap = mapped(Path(source), verb_options(tgt, options, "map").target)
    if plot is not None:
        cmap.plot(plot)
    return MapRecord(str(source), cmap, None if plot is None else str(plot))
