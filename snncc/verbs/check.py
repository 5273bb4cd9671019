"""``snncc check``: what a target loses against the float model, on a data set (or, without labels,
its agreement with the float graph)."""

from __future__ import annotations

from pathlib import Path

from snncc.errors import SnnccError
from snncc.verbs import VerbProgress, counting

AGREEMENT_RULE = "agreement without labels is measured for --target loihi"


def check_model(model: str | Path, *, target: str = "loihi", data: str | Path | None = None,
                params: str | Path | None = None, dt: float | None = None, reset: str | None = None,
                timing: str | None = None, scale: str | None = None, allow_reset_change: bool = False,
                stream: bool = False, limit: int | None = None, agreement: bool = False, density: float = 0.08,
                noise: float = 0.01, progress: VerbProgress | None = None):
    """The target's check record (``as_dict``, ``render_text``) for ``model`` on ``data``.

    With ``agreement`` or without ``data``: the target's agreement with the float graph (no labels;
    without data, ``limit or 40`` seeded random samples of ``density``, ceiling from ``noise``)."""
    from snncc.data.check_set import load_check_data
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets import capability, get_target, target_options

    model = Path(model)
    data = None if data is None else Path(data)
    graph = load_model(model, LoadOptions(params=params, dt=dt, reset=reset))
    given = {"timing": timing, "scale": scale, "allow_reset_change": allow_reset_change or None,
             "stream": stream or None, "source": str(model)}
    given = {k: v for k, v in given.items() if v is not None}   # only what the user gave (targets refuse the rest)
    if data is None or agreement:
        try:
            tgt = get_target(target)
        except SnnccError:
            raise SnnccError(AGREEMENT_RULE, field="--target") from None
        agree = capability(tgt, "agree", rule=AGREEMENT_RULE)
        x = None if data is None else load_check_data(data, graph, limit, labels=False)[0]
        return agree(graph, x, target_options(tgt, given), data=None if data is None else str(data),
                     samples=limit or 40, density=density, noise=noise)
    tgt = get_target(target)
    check = capability(tgt, "check")
    if limit is not None and limit < 1:
        raise SnnccError("must be >= 1", field="--limit")
    inputs, labels, meta = load_check_data(data, graph, limit)
    return check(graph, inputs, labels, target_options(tgt, given), data=str(data),
                 synthetic=bool(isinstance(meta, dict) and meta.get("synthetic")),
                 progress=counting(progress, len(labels), "checking"))
