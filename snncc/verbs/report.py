"""``snncc report``: what a written artefact (or a model file, compiled first) uses of its hardware; with
``--energy`` the target's ESTIMATE (not a measurement) of energy and delay per sample on a data set, a spike
file or seeded random inputs (a published measurement beside it only for the model it was measured on)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from snncc.errors import SnnccError
from snncc.verbs import VerbProgress, counting

if TYPE_CHECKING:
    from snncc.inputs import RandomSpikes
    from snncc.targets.base import Record


def report_energy(bundle: str | Path, *, target: str | None = None, energy: bool = False, data: str | Path | None = None,
                  input: str | Path | None = None, limit: int | None = None, samples: int | None = None,
                  rate: float | None = None, seed: int | None = None, params: str | Path | None = None,
                  dt: float | None = None, reset: str | None = None, progress: VerbProgress | None = None,
                  **options: object) -> Record:
    """Without ``energy``: the resource report of ``bundle`` (``snncc.api.map``'s record: a written artefact, or a
    model file compiled first with the model options and ``options``). With ``energy``: the target's energy
    report (``as_dict``, ``render_text``) of the written artefact ``bundle``. Inputs: ``data`` (a data set .npz),
    ``input`` (a spike .npy), or ``samples`` seeded random samples (default 8) with spike probability ``rate``
    (default 0.05) per channel and step, ``seed`` (default 0)."""
    from snncc.artefacts import target_for
    from snncc.inputs import RandomSpikes, load_array
    from snncc.targets import capability

    if not energy:
        for flag, value in (("--data", data), ("--input", input), ("--limit", limit), ("--samples", samples),
                            ("--rate", rate), ("--seed", seed)):
            if value is not None:
                raise SnnccError("applies to --energy (the estimate runs inputs); the resource report runs none",
                                 field=flag)
        from snncc.verbs.map import map_source

        found: Record = map_source(bundle, target=target, params=params, dt=dt, reset=reset, options=options)
        return found
    for flag, value in (("--params", params), ("--dt", dt), ("--reset", reset)):
        if value is not None:
            raise SnnccError("applies to a model file's resource report; --energy estimates a written artefact "
                             "(compile the model first)", field=flag)
    if data is not None and input is not None:
        raise SnnccError("give --data or --input, not both", field="--input")
    if limit is not None and limit < 1:
        raise SnnccError("must be >= 1", field="--limit")
    if data is not None or input is not None:
        for flag, value in (("--samples", samples), ("--rate", rate), ("--seed", seed)):
            if value is not None:
                raise SnnccError("applies only to random inputs, not with --data or --input", field=flag)
    estimate = capability(target_for(bundle, target, "estimate"), "estimate")
    x: np.ndarray | RandomSpikes
    if data is not None:
        from snncc.data.dataset_file import load_dataset

        data = Path(data)
        x, source, note = load_dataset(data)[0], str(data), f"data set {data.name}"
    elif input is not None:
        input = Path(input)
        x, source, note = load_array(input), str(input), f"input file {input.name}"
    else:
        x, source, note = RandomSpikes(8 if samples is None else samples, 0.05 if rate is None else rate,
                                       0 if seed is None else seed), None, ""
    total = x.samples if isinstance(x, RandomSpikes) else (len(x) if np.ndim(x) == 3 else 1)
    if limit is not None:
        total = min(total, limit)
    return estimate(Path(bundle), x, data=source, note=note, limit=limit,
                    progress=counting(progress, total, "emulating"))
