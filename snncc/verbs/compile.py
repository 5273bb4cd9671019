"""``snncc compile``: any supported model file -> validated IR -> a target's artefact, written atomically.

The target: ``target`` if given, else the one the output's suffix names (each target's ``output_suffix``:
``.net`` -> loihi, ``.snnir`` -> ir). A suffix that names another target than ``target`` is refused; an
output whose suffix names no target (a Jetson directory, any other name) needs ``target``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
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
    target_rule: str = "--target"      # how the target was chosen: "--target" or "the suffix '.net' of -o"
    warnings: list[str] = field(default_factory=list)   # e.g. a model silent in float (snncc.ir.liveness)

    def as_dict(self) -> dict[str, Any]:
        return {"target": self.target, "target_rule": self.target_rule, "output": self.output,
                "warnings": list(self.warnings), **self.artefact.summary()}

    def render_text(self, console) -> None:
        from snncc.targets.base import RendersText

        if isinstance(self.artefact, RendersText):
            self.artefact.render_text(console)
        else:
            console.print(self.artefact.summary())
        console.print(f"wrote {self.output}")


def resolve_target(output: str | Path, target: str | None) -> tuple[str, str]:
    """(target name, how it was chosen) from ``target`` and the suffix of ``output`` (module docstring)."""
    from snncc.errors import SnnccError
    from snncc.targets import available_targets, output_suffixes

    suffix = Path(output).suffix
    suffixes = output_suffixes()
    named = [name for name, declared in suffixes.items() if suffix and declared.lower() == suffix.lower()]
    by_suffix = named[0] if len(named) == 1 else None
    if target is not None:
        if by_suffix is not None and by_suffix != target:
            own = f" ({suffixes[target]})" if target in suffixes else ""
            raise SnnccError(f"the suffix '{suffix}' names the {by_suffix} target, not {target}: name the output "
                             f"for {target}{own} or drop --target", file=str(output), field="--target")
        return target, "--target"
    if by_suffix is None:
        known = ", ".join(f"{declared} -> {name}" for name, declared in suffixes.items())
        raise SnnccError(f"-o does not say which target to compile for: pass --target ({', '.join(available_targets())}) "
                         f"or name the output by its suffix ({known})", file=str(output), field="--target")
    return by_suffix, f"the suffix '{suffix}' of -o"


def compile_model(model: str | Path, *, output: str | Path, target: str | None = None, params: str | Path | None = None,
                  dt: float | None = None, reset: str | None = None, timing: str | None = None,
                  scale: str | None = None, allow_reset_change: bool = False, jetpack: str | None = None,
                  time_steps: int | None = None) -> CompileRecord:
    """Compile ``model`` for ``target`` (None: the target ``output``'s suffix names) and write the artefact
    to ``output``; every artefact is checked against the IR reference on the way. An option the target
    does not take is refused."""
    from snncc.frontends import LoadOptions, load_model
    from snncc.frontends.buffered import compile_buffered  # buffered classifiers have no IR graph
    from snncc.targets import capability, get_target, target_options

    target, target_rule = resolve_target(output, target)
    model = Path(model)
    given = {"timing": timing, "scale": scale, "allow_reset_change": allow_reset_change or None,
             "jetpack": jetpack, "source": str(model), "time_steps": time_steps}
    given = {k: v for k, v in given.items() if v is not None}   # only what the user gave (targets refuse the rest)
    artefact, graph, warnings = compile_buffered(model, target, given), None, []
    if artefact is None:
        from snncc.ir.liveness import calibration_warning
        from snncc.ir.timebase import sample_steps

        graph = load_model(model, LoadOptions(params=params, dt=dt, reset=reset))
        tgt = get_target(target)
        artefact = capability(tgt, "lower")(graph, target_options(tgt, given))
        if target != "ir":   # a lowered artefact claims exactness; the IR file is the model itself
            silent = calibration_warning(graph, sample_steps(graph, time_steps)[0])   # float, calibration inputs
            warnings += [silent] if silent else []
    artefact.write(output)
    return CompileRecord(target, str(output), artefact, graph, target_rule, warnings)
