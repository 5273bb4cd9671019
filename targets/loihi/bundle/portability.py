"""Portable: what lava-dl netx 0.6 loads and Lava's Loihi 1 fixed-point simulation
(``Loihi1SimCfg(select_tag="fixed_pt")``, lava-nc 0.10) runs exactly as snncc emulates it: the same
spikes, currents and voltages in every layer at every step. Stated once, here.

``netx_runnable(network)`` lists why a network is not portable (empty: portable). The rules are the
ones ``bench/studies/lava_netx_agreement.py`` measured (netx 0.6 + Lava fixed_pt against snncc's emulator,
every feature probed on its own; the definition predicted all 94 bundles it ran):

    every wgtExp / wgtExpRec is 0         netx ignores weight exponents (every weight runs at 0)
    every biasExp is 6                    netx reads the bias mantissa with exponent 6
    every refDelay is 1                   netx's LIF has no refractory period
    no feed-forward delay on a            netx hands that delay matrix to the recurrent synapse too
      recurrent layer, no recurrent delay   (a load error), and ignores delay_rec
    no weight matrix all <= 0 holding     Lava gives it the inhibitory format (-256 becomes -255)
      -256; no all-zero dense matrix        / netx cannot load it (a division by zero)
    no always-on input axons              netx does not know them: its driver would have to hold
                                            them at 1 (measured identical when it does)

Not static, so not here: a step's input q beyond 21 bits + sign (Lava does not wrap it; snncc's
emulator counts q wraps) and u landing exactly on -2**23. Per-neuron thresholds and decays run
identically in Lava's CPU simulation (measured), though Lava's LIF states one value per process.

Each reason says whether the scale rule caused it (``by_rule``: another rule may avoid it; weight and
bias exponents and the weights' format are the quantization's) or the model needs it whatever the rule
(``by_rule`` False: its refractory period, delays, biases through always-on inputs), so the ``auto``
scale rule can keep to portable rules and say what a model needs that netx lacks.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from snncc.targets.loihi import chip
from snncc.targets.loihi.network import LoihiNetwork

NOT_RUNNABLE = "not runnable by netx as written"
PER_NEURON_NOTE = "one value per neuron"   # a bundle note on per-neuron registers, which Lava's CPU model runs as written
NETX_MIN_WEIGHT = -256     # an all-negative matrix holding it is given Lava's inhibitory format (at most -255)


@dataclass(frozen=True)
class NetxGap:
    """One reason netx would not run a network as written."""

    feature: str        # what netx lacks, e.g. "weight exponents", "refractory period"
    where: str          # the bundle path concerned
    by_rule: bool       # caused by the scale rule (another rule may avoid it), else needed by the model

    def __str__(self) -> str:
        return f"{self.where}: {self.feature}"

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _weights_gaps(i: int, key: str, w) -> list[NetxGap]:
    if w is None:
        return []
    w = np.asarray(w)
    if w.size and np.all(w <= 0) and np.any(w == NETX_MIN_WEIGHT):
        return [NetxGap("an all-negative weight matrix holding -256 (Lava's inhibitory format holds -255)",
                        f"/layer/{i}/{key}", by_rule=True)]
    return []


def netx_runnable(network: LoihiNetwork) -> list[NetxGap]:
    """Why netx 0.6 + Lava fixed_pt would not run ``network`` as snncc emulates it (module docstring); [] when
    portable."""
    gaps: list[NetxGap] = []
    if network.layers[0].always_on:
        gaps.append(NetxGap("always-on input axons (netx does not know them; its driver must hold them at 1)",
                            "/layer/0/alwaysOn", by_rule=False))
    for i, lay in enumerate(network.layers[1:], start=1):
        for key, exp, w in (("wgtExp", lay.wgt_exp, lay.weight), ("wgtExpRec", lay.wgt_exp_rec, lay.weight_rec)):
            if w is not None and np.any(np.asarray(exp) != 0):
                e = np.asarray(exp)
                per = "per-synapse weight exponents" if e.ndim and e.min() != e.max() else "a weight exponent other than 0"
                gaps.append(NetxGap(f"{per} (netx runs every weight at wgtExp 0)", f"/layer/{i}/neuron/{key}",
                                    by_rule=True))
        if lay.bias is not None and np.any(np.asarray(lay.bias) != 0) and lay.bias_exp != chip.NETX_BIAS_EXP:
            gaps.append(NetxGap(f"biasExp {lay.bias_exp} (netx reads biases with exponent {chip.NETX_BIAS_EXP})",
                                f"/layer/{i}/neuron/biasExp", by_rule=True))
        if lay.ref_delay != 1:
            gaps.append(NetxGap(f"refDelay {lay.ref_delay} (netx's LIF has no refractory period)",
                                f"/layer/{i}/neuron/refDelay", by_rule=False))
        if lay.weight_rec is not None:
            if np.any(np.asarray(lay.delay) != 0):
                gaps.append(NetxGap("a feed-forward delay on a recurrent layer (netx 0.6 cannot load it)",
                                    f"/layer/{i}/delay", by_rule=False))
            if np.any(np.asarray(lay.delay_rec) != 0):
                gaps.append(NetxGap("recurrent synaptic delays (netx ignores delay_rec)", f"/layer/{i}/delay_rec",
                                    by_rule=False))
        gaps += _weights_gaps(i, "weight", lay.weight) + _weights_gaps(i, "weight_rec", lay.weight_rec)
        everything = [np.asarray(lay.weight)] + ([np.asarray(lay.weight_rec)] if lay.weight_rec is not None else [])
        if not any(w.any() for w in everything):
            gaps.append(NetxGap("an all-zero weight matrix (netx 0.6 cannot load it)", f"/layer/{i}/weight",
                                by_rule=False))
    return gaps


def portability_line(gaps: list[NetxGap]) -> str:
    """The one line a report prints."""
    if not gaps:
        return ("portable: lava-dl netx 0.6 and Lava's fixed-point simulation run this bundle as written "
                "(measured rules: bench/studies/lava_netx_agreement.py)")
    features = list(dict.fromkeys(g.feature.split(" (")[0] for g in gaps))
    return f"{NOT_RUNNABLE}: {', '.join(features)} ({'; '.join(str(g) for g in gaps)})"
