"""``snncc report --energy``'s work: a bundle mapped, emulated on inputs fitted to it, and its energy and delay
per sample ESTIMATED (``energy.py``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from snncc.targets.kit import SnnccError


@dataclass
class EnergyReport:
    """The estimate and the core map it was made on (``as_dict`` is ``snncc report --json``)."""

    bundle: str
    estimate: Any            # EnergyEstimate
    n_cores: int
    n_chips: int
    lower_bound: int

    def as_dict(self) -> dict[str, Any]:
        return {"bundle": self.bundle, "estimate": self.estimate.to_dict(),
                "core_map": {"n_cores": self.n_cores, "n_chips": self.n_chips, "lower_bound": self.lower_bound}}

    def render_text(self, console) -> None:
        self.estimate.render_text(console)


def estimate_bundle(source: Path, inputs, *, data: str | None = None, note: str = "", limit: int | None = None,
                    progress: Callable[[int], None] | None = None) -> EnergyReport:
    """``inputs``: an array (T, C) or (B, T, C) read from ``data``, or ``snncc.inputs.RandomSpikes`` drawn
    at the bundle's tSample and input width. The first ``limit`` samples are used, fitted to the bundle
    (``fit.py``); ``progress(n)`` after every n samples emulated."""
    from snncc.targets.kit.inputs import RandomSpikes
    from snncc.targets.loihi.estimate.energy import emulate_and_estimate
    from snncc.targets.loihi.emulation.fit import fit_to_bundle
    from snncc.targets.loihi.mapping.partition import map_network
    from snncc.targets.loihi.bundle.read import read_bundle

    network = read_bundle(Path(source))
    if isinstance(inputs, RandomSpikes):
        x, data, note = inputs.draw(network.t_sample, network.input_width), "<random>", inputs.note()
    else:
        x = inputs
    x = np.asarray(x)
    if limit is not None:
        x = x[:limit]
    x, fit = fit_to_bundle(x, network, str(data))
    if fit:
        note = f"{note} ({fit})"
    try:
        cmap = map_network(network)
    except SnnccError as err:
        raise err.with_file(str(source)) from None
    done = [0]

    def advanced(completed: int) -> None:
        if progress is not None:
            progress(completed - done[0])
        done[0] = completed

    est = emulate_and_estimate(cmap.network, cmap, x, note, progress=advanced)
    if cmap.transforms:
        est.assumptions.append("the network was emulated with the fan-in relays the map inserted (see snncc map)")
    return EnergyReport(str(source), est, cmap.n_cores, cmap.n_chips, cmap.lower_bound)
