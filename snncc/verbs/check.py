"""``snncc check``: what a target loses against the float model, on a data set (or, without labels,
its agreement with the float graph)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError
from snncc.verbs import VerbProgress, counting

if TYPE_CHECKING:
    from snncc.targets.base import Record

OFFERS = ("check", "agree")          # the capabilities whose options ``snncc check`` offers


def check_model(model: str | Path, *, target: str = "loihi", data: str | Path | None = None,
                params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
                limit: int | None = None, agreement: bool = False, progress: VerbProgress | None = None,
                **options: object) -> Record:
    """The target's check record (``as_dict``, ``render_text``) for ``model`` on ``data``.

    With ``agreement`` or without ``data``: the target's agreement with the float graph (no labels;
    without data, ``samples`` (default: ``limit`` or 40) seeded random samples of ``density``, the
    ceiling from ``noise``: the agreement's options). ``options``: the target's own (``scale``,
    ``stream``, ...) and the agreement's; one that does not apply is refused."""
    from snncc.data.check_set import load_check_data
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets import AgreementOptions, capability, get_target, offering, verb_options

    model = Path(model)
    where = None if data is None else Path(data)
    if limit is not None and limit < 1:
        raise SnnccError("must be >= 1", field="--limit")
    graph = load_model(model, LoadOptions(params=None if params is None else Path(params), dt=dt, reset=reset))
    given = {**options, "source": str(model)}
    if where is None or agreement:
        rule = ("agreement without labels is measured for "
                + (" or ".join(f"--target {name}" for name in offering("agree")) or "no installed target"))
        try:
            tgt = get_target(target)
        except SnnccError:
            raise SnnccError(rule, field="--target") from None
        agree = capability(tgt, "agree", rule=rule)
        if where is not None and options.get("samples") is not None:
            raise SnnccError("applies only to random inputs, not with --data (use --limit)", field="--samples")
        if limit is not None and options.get("samples") is not None:
            raise SnnccError("give --samples or --limit, not both", field="--samples")
        if options.get("samples") is None and limit is not None:
            given["samples"] = limit
        split = verb_options(tgt, given, "agree", OFFERS)
        x = None if where is None else load_check_data(where, graph, limit, labels=False)[0]
        return agree(graph, x, split.target, split.of(AgreementOptions), data=None if where is None else str(where))
    tgt = get_target(target)
    check = capability(tgt, "check")
    split = verb_options(tgt, given, "check", OFFERS)
    inputs, labels, meta = load_check_data(where, graph, limit)
    assert labels is not None
    return check(graph, inputs, labels, split.target, data=str(where),
                 synthetic=bool(isinstance(meta, dict) and meta.get("synthetic")),
                 progress=counting(progress, len(labels), "checking"))
