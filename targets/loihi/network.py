"""A Loihi network as plain data: what the bundle stores, the emulator runs and the mapper places.

Layer 0 is the input (``n`` input axons, no neurons). Every other layer is a population of CUBA
compartments fed by the previous layer through ``weight`` (out, in) and, for ``dense_rec``, by
itself through ``weight_rec`` (n, n). Integer fields follow Loihi's registers:

    w_chip = weight * 2**(6 + wgt_exp)         weight: even integers in [-256, 254]
    threshold on chip = v_th_mant * 2**6
    u <- u*(4096 - i_decay)/4096 + q ;  v <- v*(4096 - v_decay)/4096 + u + bias * 2**bias_exp
    ref_delay: steps a neuron stays silent after a spike, including the spike step (1 = none)
    delay / delay_rec: extra synaptic delay in steps (0..62) on top of the one-step delivery;
    a scalar for the whole projection or an int array shaped like the weights
    v_th_mant / i_decay / v_decay: an int for the layer, or an (n,) int array (a compartment
    profile per neuron; the core map keeps at most 8 threshold / 32 compartment profiles a core)
    wgt_exp / wgt_exp_rec: an int, or an int array shaped like the weights when a projection
    uses two synapse formats (a fine exponent for the bulk, a coarse one for outliers)
    always_on: the layer's last ``always_on`` units are bias sources (``lowering/bias_sources.py``): input
    axons the driver holds at 1 every step, or compartments that fire on their own

The ranges are ``chip.py``'s; vmin / vmax default to its V_MIN / V_MAX when a layer is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.loihi import chip

LAYER_KINDS = ("input", "dense", "dense_rec")


@dataclass(eq=False)
class LoihiLayer:
    name: str
    kind: str
    n: int
    weight: np.ndarray | None = None        # (n, n_prev) even ints, None for the input layer
    weight_rec: np.ndarray | None = None    # (n, n) even ints for dense_rec
    wgt_exp: Any = 0                        # int, or int array like weight (split exponents)
    wgt_exp_rec: Any = 0                    # snncc extension: exponent of the recurrent matrix
    delay: Any = 0                          # extra synaptic delay (steps), int or int array like weight
    delay_rec: Any = 0
    bias: np.ndarray | None = None          # bias mantissa per neuron
    bias_exp: int = chip.NETX_BIAS_EXP      # netx reads bias with exponent 6
    v_th_mant: Any = 0                      # int, or (n,) int array (per-neuron profiles)
    i_decay: Any = 0
    v_decay: Any = 0
    ref_delay: int = 1
    vmin: int = field(default_factory=lambda: chip.V_MIN)
    vmax: int = field(default_factory=lambda: chip.V_MAX)
    always_on: int = 0

    @property
    def model_n(self) -> int:
        """Units of the model itself (the layer without its always-on bias sources)."""
        return self.n - self.always_on

    @property
    def fan_in(self) -> int:
        """Input axons this layer's neurons listen to (feed-forward plus recurrent)."""
        if self.weight is None:
            return 0
        return int(self.weight.shape[1] + (self.n if self.weight_rec is not None else 0))


@dataclass(eq=False)
class LoihiNetwork:
    layers: list[LoihiLayer]
    t_sample: int
    metadata: dict[str, Any] = field(default_factory=dict)
    core_map: dict[str, Any] | None = None   # set by the mapper (targets/loihi/mapping/partition.py)

    @property
    def input_width(self) -> int:
        """Channels of data a user supplies (the always-on bias axons are added by the driver)."""
        return self.layers[0].model_n

    def drive(self, x: np.ndarray) -> np.ndarray:
        """(B, T, input_width) data -> (B, T, axons): the always-on bias axons appended as ones."""
        k = self.layers[0].always_on
        if not k:
            return x
        return np.concatenate([x, np.ones(x.shape[:2] + (k,), x.dtype)], axis=2)

    @property
    def n_outputs(self) -> int:
        return self.layers[-1].n


def same_registers(a: LoihiNetwork, b: LoihiNetwork) -> bool:
    """Whether two networks hold the same layers, register for register (what the emulator runs; the metadata and
    core map aside)."""
    from dataclasses import fields

    if a.t_sample != b.t_sample or len(a.layers) != len(b.layers):
        return False
    for la, lb in zip(a.layers, b.layers):
        for f in fields(LoihiLayer):
            x, y = getattr(la, f.name), getattr(lb, f.name)
            if (x is None) != (y is None) or (x is not None and not np.array_equal(np.asarray(x), np.asarray(y))):
                return False
    return True

