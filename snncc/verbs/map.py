"""``snncc map``: place a bundle (or a model, lowered first) on the target's cores and report the core map."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class MapRecord:
    source: str
    core_map: Any            # the target's map (to_dict, render_text, plot)
    plot: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return {"source": self.source, **self.core_map.to_dict()}

    def render_text(self, console) -> None:
        self.core_map.render_text(console)
        if self.plot is not None:
            console.print(f"wrote {self.plot}")


def map_cores(source: str | Path, *, target: str = "loihi", plot: str | Path | None = None,
              timing: str | None = None, scale: str | None = None) -> MapRecord:
    """The core map of ``source``; ``plot`` also draws utilisation per core as a PNG (atomically).
    ``timing``/``scale`` apply only when ``source`` is a model file (lowered first)."""
    from snncc.targets import capability, get_target

    given = {k: v for k, v in {"timing": timing, "scale": scale}.items() if v is not None}
    cmap = capability(get_target(target), "map")(Path(source), given)
    if plot is not None:
        cmap.plot(plot)
    return MapRecord(str(source), cmap, None if plot is None else str(plot))
