"""``snncc compile``: any supported model file -> validated IR -> a target's artefact, written atomically."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class CompileRecord:
    """The artefact written to ``output`` (and the IR graph it was lowered from; None for a buffered
    classifier, which has no IR graph)."""

    target: str
    output: str
    artefact: Any
    graph: Any = None

    def as_dict(self) -> dict[str, Any]:
        return {"target": self.target, "output": self.output, **self.artefact.summary()}

    def render_text(self, console) -> None:
        from snncc.targets.base import RendersText

        if isinstance(self.artefact, RendersText):
            self.artefact.render_text(console)
        else:
            console.print(self.artefact.summary())
        console.print(f"wrote {self.output}")


def compile_model(model: str | Path, *, output: str | Path, target: str = "ir", params: str | Path | None = None,
                  dt: float | None = None, reset: str | None = None, timing: str | None = None,
                  scale: str | None = None, allow_reset_change: bool = False, jetpack: str | None = None,
                  time_steps: int | None = None) -> CompileRecord:
    """Compile ``model`` for ``target`` and write the artefact to ``output``; every artefact is checked
    against the IR reference on the way. An option the target does not take is refused."""
    from snncc.frontends import LoadOptions, load_model
    from snncc.frontends.buffered import compile_buffered  # buffered classifiers have no IR graph
    from snncc.targets import capability, get_target, target_options

    model = Path(model)
    given = {"timing": timing, "scale": scale, "allow_reset_change": allow_reset_change or None,
             "jetpack": jetpack, "source": str(model), "time_steps": time_steps}
    given = {k: v for k, v in given.items() if v is not None}   # only what the user gave (targets refuse the rest)
    artefact, graph = compile_buffered(model, target, given), None
    if artefact is None:
        graph = load_model(model, LoadOptions(params=params, dt=dt, reset=reset))
        tgt = get_target(target)
        artefact = capability(tgt, "lower")(graph, target_options(tgt, given))
    artefact.write(output)
    return CompileRecord(target, str(output), artefact, graph)
