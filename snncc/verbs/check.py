"""``snncc check``: what a written artefact loses against the float model it came from, measured by
running the artefact again: on a data set (accuracy and its causes), or without labels (its
agreement with the float model).

With ``artefact`` (``--artefact PATH``), that artefact is measured; its target follows from it
(each target recognises its own: capability ``identify``), and one compiled from another model
file is refused. Without it, the model is compiled exactly as ``snncc compile`` would (the same
options, hence the same artefact and hash) into a temporary directory, and that written artefact
is measured. Either way the record names the artefact's SHA-256 (``snncc.artefacts``).
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import InternalError, SnnccError
from snncc.verbs import VerbProgress, counting

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.targets.base import Record, Target

OFFERS = ("check", "agree", "lower")    # the capabilities whose options ``snncc check`` offers (lower: compiling)
AGREEMENT_RULE = "has no agreement without labels (capability 'agree'); give --data with labels"


@dataclass
class ArtefactCheck:
    """The target's record of the measured artefact, with what was measured: ``artefact`` holds path
    (None when check compiled it into a temporary directory), target, description, sha256, sha256_rule,
    compiled_by_check, source_sha256 and source_note; ``input_layout`` what was done to take the data
    in the model's own shape (None: nothing)."""

    artefact: dict[str, object]
    record: Record
    input_layout: str | None = None

    def as_dict(self) -> dict[str, object]:
        record = self.record.as_dict()
        clash = {"artefact", "input_layout"} & set(record)
        if clash:   # what was measured is this verb's to say; a target's record may not overwrite it
            raise InternalError(f"the check record holds {sorted(clash)}, which check itself reports",
                                field="check")
        return {"artefact": self.artefact, "input_layout": self.input_layout, **record}

    def render_text(self, console: Console) -> None:
        a = self.artefact
        where = ("compiled here exactly as `snncc compile` would, into a temporary directory" if a["compiled_by_check"]
                 else a["path"])
        console.print(f"measured artefact: {a['description'] or a['target']} ({where})", markup=False, soft_wrap=True)
        console.print(f"  SHA-256 {a['sha256']} ({a['sha256_rule']})", markup=False, soft_wrap=True)
        if a.get("source_note"):
            console.print(f"  note: {a['source_note']}", markup=False, soft_wrap=True)
        if self.input_layout:
            console.print(f"  input: {self.input_layout}", markup=False, soft_wrap=True)
        self.record.render_text(console)


def _refuse_lowering(target: Target, given: Mapping[str, object]) -> None:
    """With a written artefact, an option compile reads (declared for ``lower``) is fixed: refused in one line."""
    from snncc.targets.base import declared_options

    for name, spec in declared_options(target.options_type).items():
        if "lower" in spec.capabilities and given.get(name) not in (None, False):
            raise SnnccError("does not apply to a written artefact (compile fixed it); give it to compile, or check "
                             "the model without --artefact", field=spec.flag)


def check_model(model: str | Path, *, artefact: str | Path | None = None, target: str | None = None,
                data: str | Path | None = None, params: str | Path | None = None, dt: float | None = None,
                reset: str | None = None, limit: int | None = None, agreement: bool = False,
                progress: VerbProgress | None = None, **options: object) -> ArtefactCheck:
    """The measured artefact's record (``as_dict``, ``render_text``) for ``model`` on ``data``.

    With ``agreement`` or without ``data``: the artefact's agreement with the float model (no labels;
    without data, ``samples`` (default: ``limit``, else ``snncc.measure.agreement.default_samples``)
    seeded random samples of ``density``, the ceiling from ``noise``: the agreement's options).
    ``artefact``: a written artefact to measure; else the model is compiled here as compile would,
    with the target's compile options among ``options`` (``scale``, ``time_steps``, ...). ``options``:
    the target's own and the agreement's; one that does not apply is refused."""
    from snncc.artefacts import ArtefactIdentity, artefact_sha256, check_source, identify, identify_own
    from snncc.targets.kit.measured import compiled as compiled_artefact
    from snncc.data.check_set import load_check_data
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets import DEFAULT_TARGET, AgreementOptions, capability, get_target, verb_options

    model = Path(model)
    where = None if data is None else Path(data)
    if limit is not None and limit < 1:
        raise SnnccError("must be >= 1", field="--limit")
    graph = load_model(model, LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    given: dict[str, object] = {**options, "source": str(model)}
    labelled = where is not None and not agreement
    use = "check" if labelled else "agree"
    if not labelled:
        if where is not None and options.get("samples") is not None:
            raise SnnccError("applies only to random inputs, not with --data (use --limit)", field="--samples")
        if limit is not None and options.get("samples") is not None:
            raise SnnccError("give --samples or --limit, not both", field="--samples")
        if options.get("samples") is None and limit is not None and where is None:
            given["samples"] = limit
    identity: ArtefactIdentity | None = None
    source_note = None
    if artefact is not None:
        tgt, identity = identify(artefact, target)
        _refuse_lowering(tgt, given)
        split = verb_options(tgt, given, use, OFFERS)
        source_note = check_source(identity, graph, model)
        written: contextlib.AbstractContextManager[Path] = contextlib.nullcontext(Path(artefact))
    else:
        tgt = get_target(target or DEFAULT_TARGET)
        split = verb_options(tgt, given, (use, "lower"), OFFERS)   # the options of compiling it too
        written = compiled_artefact(tgt, graph, split.target)
    if labelled:
        check = capability(tgt, "check")
    else:
        agree = capability(tgt, "agree", rule=f"target '{tgt.name}' {AGREEMENT_RULE}")
    layout = None
    # the data read (and refused) before any compile: a bad file costs no lowering
    inputs = labels = None
    meta: object = None
    if where is not None:
        inputs, labels, meta = load_check_data(where, graph, limit, labels=labelled)
        found = meta.get("input_layout") if isinstance(meta, dict) else None
        layout = found if isinstance(found, str) else None
    with written as path:
        if identity is None:
            identity = identify_own(tgt, path) or ArtefactIdentity(tgt.name, str(path))
        sha, rule = artefact_sha256(path, identity.files or None)
        if labelled:
            assert where is not None and inputs is not None and labels is not None
            record: Record = check(graph, inputs, labels, split.target, artefact=path, data=str(where),
                                     synthetic=bool(isinstance(meta, dict) and meta.get("synthetic")),
                                     progress=counting(progress, len(labels), "checking"))
        else:
            x = inputs
            how = split.of(AgreementOptions)
            total = len(x) if x is not None else (how.samples or 0)
            record = agree(graph, x, split.target, how, artefact=path,
                             data=None if where is None else str(where),
                             progress=counting(progress, total, "measuring agreement") if total else None)
    described: dict[str, object] = {
        "path": None if artefact is None else str(artefact), "target": tgt.name, "description": identity.description,
        "sha256": sha, "sha256_rule": rule, "compiled_by_check": artefact is None,
        "source_sha256": identity.source_sha256, "source_note": source_note}
    return ArtefactCheck(described, record, layout)
