"""``snncc compile``: any supported model file -> validated IR -> a target's artefact, written atomically.

The target: ``target`` if given, else the one the output's suffix names (each target's ``output_suffix``:
``.net`` -> loihi, ``.snnir`` -> ir). A suffix that names another target than ``target`` is refused; an
output whose suffix names no target (a Jetson directory, any other name) needs ``target``.

With ``finetune=True`` the target's ``finetune`` capability replaces ``lower`` (``docs/finetune.md``):
the lowered model trained through the chip's arithmetic towards the float graph as trained; its
options (``FinetuneOptions``: ``finetune_out``, ``data``, ``density``, ``device``, ...) are refused
without it, and a target without the capability refuses ``finetune`` in one line.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError, one_line
from snncc.progress import Progress

OFFERS = ("lower", "finetune")       # the capabilities whose options ``snncc compile`` offers

if TYPE_CHECKING:
    import numpy as np
    from rich.console import Console

    from snncc.ir.graph import Graph
    from snncc.targets import VerbOptions
    from snncc.targets.base import Artefact, FinetunedArtefact, Model, Target


@dataclass
class CompileRecord:
    """The artefact written to ``output`` (and the IR graph it was lowered from; None for a buffered
    classifier, which has no IR graph)."""

    target: str
    output: str
    artefact: Artefact
    graph: Graph | None = None
    target_rule: str = "--target"      # how the target was chosen: "--target" or "the suffix '.net' of -o"
    warnings: list[str] = field(default_factory=list)   # e.g. a model silent in float (snncc.ir.liveness)
    sha256: str | None = None          # of the written artefact (snncc.artefacts.artefact_sha256)
    sha256_rule: str | None = None
    finetune_out: str | None = None    # where the adapted float graph was written (NIR), with --finetune-out

    def as_dict(self) -> dict[str, object]:
        hashed = {"sha256": self.sha256, "sha256_rule": self.sha256_rule} if self.sha256 else {}
        return {"target": self.target, "target_rule": self.target_rule, "output": self.output,
                "warnings": list(self.warnings), **hashed, **self.artefact.summary(),
                **({"finetune_out": self.finetune_out} if self.finetune_out else {})}

    def render_text(self, console: Console) -> None:
        from snncc.targets.base import RendersText

        if isinstance(self.artefact, RendersText):
            self.artefact.render_text(console)
        else:
            console.print(self.artefact.summary())
        console.print(f"wrote {one_line(self.output)}" + (f" (SHA-256 {self.sha256})" if self.sha256 else ""),
                      markup=False)
        if self.finetune_out:
            console.print(f"wrote {one_line(self.finetune_out)} (the adapted float graph, NIR)", markup=False)


def resolve_target(output: str | Path, target: str | None) -> tuple[str, str]:
    """(target name, how it was chosen) from ``target`` and the suffix ending ``output``'s name (module docstring;
    the longest declared suffix that ends the name wins, so ``.null.json`` is matched as a whole)."""
    from snncc.targets import available_targets, output_suffixes, suffix_target

    by_suffix, suffix = suffix_target(str(output))
    suffixes = output_suffixes()
    if target is not None:
        if by_suffix is not None and by_suffix != target and not str(output).lower().endswith(
                suffixes.get(target, "\0").lower()):
            own = f" ({suffixes[target]})" if target in suffixes else ""
            raise SnnccError(f"the suffix '{suffix}' names the {by_suffix} target, not {target}: name the output "
                             f"for {target}{own} or drop --target", file=str(output), field="--target")
        return target, "--target"
    if by_suffix is None:
        known = ", ".join(f"{declared} -> {name}" for name, declared in suffixes.items())
        raise SnnccError(f"-o does not say which target to compile for: pass --target ({', '.join(available_targets())}) "
                         f"or name the output by its suffix ({known})", file=str(output), field="--target")
    return by_suffix, f"the suffix '{suffix}' of -o"


def compile_model(model: str | Path, *, output: str | Path, target: str | None = None,
                  params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
                  progress: Progress | None = None, **options: object) -> CompileRecord:
    """Compile ``model`` for ``target`` (None: the target ``output``'s suffix names) and write the artefact
    to ``output``; every artefact is checked against the IR reference on the way. ``options``: the
    target's own (``scale="split"``, ``jetpack="6.1"``, ...; ``snncc.targets.offered_options(["lower"])``
    lists them); one the target does not take is refused. ``progress(done, total, phase)`` as the target
    lowers and validates (and fine-tunes: ``finetune=True``, the module doc)."""
    from snncc.atomic import preflight
    from snncc.frontends import LoadOptions
    from snncc.frontends.buffered import BufferedModel, load_compilable
    from snncc.targets import capability, get_target, offering, takers, verb_options

    name, target_rule = resolve_target(output, target)
    tuning = bool(options.get("finetune"))
    if tuning and name not in offering("finetune"):
        takers_ = " or ".join(f"--target {t}" for t in offering("finetune")) or "no installed target"
        raise SnnccError(f"target '{name}' has no fine-tuning in this snncc (it is offered by {takers_})",
                         field="--finetune")
    # an output that cannot be written (or an existing directory the target would not replace) is refused now, not
    # after the compilation and its checks
    tgt = get_target(name)
    preflight(output, directory=getattr(tgt, "output_kind", "file") == "directory",
              replaceable=getattr(tgt, "replace_refusal", None))
    model = Path(model)
    tuned_out = options.get("finetune_out")
    if tuning and tuned_out is not None:
        data = options.get("data")
        _check_finetune_out(Path(str(tuned_out)), [model] + ([Path(str(data))] if data is not None else []),
                            Path(output))
    loaded = load_compilable(model, LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    kind = getattr(loaded, "model_kind", "graph")
    if kind not in getattr(tgt, "model_kinds", ("graph",)):
        assert isinstance(loaded, BufferedModel)
        only = " or ".join(f"--target {t}" for t in takers(kind)) or "a target that takes it"
        raise SnnccError(f"a {loaded.kind} (convolutional, buffered) has no IR graph and compiles only with {only}",
                         file=str(model), field="--target")
    given: Mapping[str, object] = {**options, "source": str(model)}
    split = verb_options(tgt, given, OFFERS if tuning else "lower", OFFERS)
    settings = split.target
    if tuning:
        artefact: Artefact = _finetune(tgt, loaded, split, progress)
    else:
        artefact = capability(tgt, "lower")(loaded, settings, progress=progress)
    warnings: list[str] = []
    if not isinstance(loaded, BufferedModel) and name != "ir":   # a lowered artefact claims exactness
        from snncc.ir.liveness import calibration_warning
        from snncc.ir.timebase import sample_steps
        from snncc.targets.base import KnowsFloatActivity

        steps = getattr(settings, "time_steps", None)      # the target's steps option, where it declares one
        t = sample_steps(loaded, steps if isinstance(steps, int) else None)[0]
        known = artefact.float_calibration_activity(t) if isinstance(artefact, KnowsFloatActivity) else None
        silent = calibration_warning(loaded, t, known)
        warnings += [silent] if silent else []
    adapted = None
    if tuning and tuned_out is not None:     # built first: a graph NIR cannot hold is refused before any write
        from snncc.exporters.nir import nir_bytes
        from snncc.targets.base import FinetunedArtefact

        assert isinstance(artefact, FinetunedArtefact)
        adapted = nir_bytes(artefact.adapted_graph())[0]
    artefact.write(output)
    if adapted is not None:
        from snncc.atomic import write_bytes_atomic

        write_bytes_atomic(Path(str(tuned_out)), adapted)
    return CompileRecord(name, str(output), artefact, None if isinstance(loaded, BufferedModel) else loaded,
                         target_rule, warnings, *_written_hash(tgt, output),
                         finetune_out=None if tuned_out is None else str(tuned_out))


def _written_hash(target: Target, output: str | Path) -> tuple[str | None, str | None]:
    """(SHA-256, rule) of the artefact just written, as ``snncc check`` states it (a directory: over the
    files the target's ``identify`` lists); (None, None) for output that is no file or directory (-o /dev/null)."""
    from snncc.artefacts import artefact_sha256, identify_own

    path = Path(output)
    if not (path.is_file() or path.is_dir()):
        return None, None
    identity = identify_own(target, path)
    digest, rule = artefact_sha256(path, identity.files if identity is not None else None)
    return digest, rule


def _check_finetune_out(path: Path, inputs: list[Path], output: Path) -> None:
    """``--finetune-out`` is a new file: never the model or the data (``inputs``), never ``-o``, writable."""
    from snncc.atomic import preflight

    if any(path.resolve() == given.resolve() for given in inputs):
        raise SnnccError("is an input (the model or --data); fine-tuning never overwrites it: give a new name",
                         file=str(path), field="--finetune-out")
    if path.resolve() == output.resolve():
        raise SnnccError("is also -o: give the adapted graph its own name", file=str(path), field="--finetune-out")
    preflight(path)


def _finetune(tgt: Target, loaded: Model, split: VerbOptions, progress: Progress | None) -> FinetunedArtefact:
    """The target's ``finetune`` on the inputs ``data`` names (labels where it has them) or, without data,
    on the seeded random spikes of ``FinetuneOptions``."""
    from snncc.targets import FinetuneOptions, capability

    how = split.of(FinetuneOptions)
    inputs = labels = None
    if how.data is not None and how.density is not None:
        raise SnnccError("applies only to seeded random inputs, not with --data", field="--density")
    if how.data is not None:
        inputs, labels = _finetune_data(Path(how.data), loaded)
    tune = capability(tgt, "finetune")
    return tune(loaded, inputs, split.target, how, labels=labels, data=how.data, progress=progress)


def _finetune_data(path: Path, graph: Model) -> tuple[np.ndarray, np.ndarray | None]:
    """(inputs, labels or None) from the files ``snncc check`` takes: a labelled data set, else an .npz of
    inputs (the labelled reading's refusal when neither reads)."""
    from snncc.data.check_set import load_check_data

    if not path.is_file():
        raise SnnccError("file does not exist", file=str(path), field="--data")
    try:
        inputs, labels, _ = load_check_data(path, graph)
    except SnnccError as labelled:
        try:
            inputs, labels, _ = load_check_data(path, graph, labels=False)
        except SnnccError:
            raise labelled from None
    return inputs, labels
