"""Portable: what lava-dl netx 0.6 loads and Lava's Loihi 1 fixed-point simulation
(``Loihi1SimCfg(select_tag="fixed_pt")``) runs exactly as snncc emulates it. Stated once, here.

``netx_runnable(network)`` lists why a network is not portable (empty: portable). The rule is an
ASSUMPTION until ``bench/lava_netx_agreement.py`` (lava-dl netx 0.6 + Lava fixed_pt against snncc's
emulator) reports measured facts, and is adjusted here when it does:

    one weight exponent per layer          (``global``, ``per-layer``; not ``split`` or ``fine``,
                                            which give each synapse its own exponent)
    one threshold and decay value per layer (no per-neuron compartment profiles)
    no always-on bias sources              (current-placed biases need an input axon held at 1 or
                                            self-firing compartments, which a netx driver lacks)

Each reason says whether the scale rule caused it (``by_rule``: another rule avoids it) or the
model needs it (every rule has it), so the ``auto`` scale rule can keep to portable rules and say
what a model needs that netx lacks.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from snncc.targets.loihi.network import LoihiNetwork

NOT_RUNNABLE = "not runnable by netx as written"


@dataclass(frozen=True)
class NetxGap:
    """One reason netx would not run a network as written."""

    feature: str        # "per-synapse weight exponents" | "per-neuron registers" | "always-on bias sources"
    where: str          # the bundle path concerned
    by_rule: bool       # caused by the scale rule (another rule avoids it), else needed by the model

    def __str__(self) -> str:
        return f"{self.where}: {self.feature}"

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def netx_runnable(network: LoihiNetwork) -> list[NetxGap]:
    """Why netx 0.6 would not run ``network`` as written (see the module docstring); [] when portable."""
    gaps: list[NetxGap] = []
    if network.layers[0].always_on:
        gaps.append(NetxGap("always-on bias sources", "/layer/0/alwaysOn", by_rule=False))
    for i, lay in enumerate(network.layers[1:], start=1):
        for key, exp, w in (("wgtExp", lay.wgt_exp, lay.weight), ("wgtExpRec", lay.wgt_exp_rec, lay.weight_rec)):
            if w is not None and np.ndim(exp) and np.unique(np.asarray(exp)).size > 1:
                gaps.append(NetxGap("per-synapse weight exponents", f"/layer/{i}/neuron/{key}", by_rule=True))
        per_neuron = [key for key, value in (("vThMant", lay.v_th_mant), ("iDecay", lay.i_decay),
                                             ("vDecay", lay.v_decay)) if np.ndim(value) and np.unique(value).size > 1]
        if per_neuron:
            gaps.append(NetxGap("per-neuron registers", f"/layer/{i}/neuron/{{{', '.join(per_neuron)}}}",
                                by_rule=False))
        if lay.always_on:
            gaps.append(NetxGap("always-on bias sources", f"/layer/{i}/alwaysOn", by_rule=False))
    return gaps


def portability_line(gaps: list[NetxGap]) -> str:
    """The one line a report prints."""
    if not gaps:
        return "portable: netx 0.6 runs this bundle as written (one weight exponent, threshold and decay per layer)"
    features = sorted({g.feature for g in gaps})
    return f"{NOT_RUNNABLE}: {', '.join(features)} ({'; '.join(str(g) for g in gaps)})"
