"""Sigma-delta relay neurons: a third basis function for Xylo's memoryless-readout neurons.

A memoryless-readout neuron (``chip_form.hidden_single``) answers an input spike with two exponentials
``u_1 a_1^(n+1) + u_2 a_2^(n+1)`` on Xylo's grid ``a = 1 - 2^-d``. A float kernel with a pole off the grid
is fitted poorly by two of them: the NIR paper's Braille RSNN (alpha 0.75, beta 0.85) loses about 20 points
of argmax agreement to its membrane pole alone (0.85 between the grid's 0.75 and 0.875). Any linear path
on the chip has only grid poles, but a *cascade* of two grid filters -- the shape of a CUBA kernel, the
current's decay then the membrane's -- fits it with small weights. A relay supplies the cascade:

    one hidden neuron per presynaptic channel z (the input's channels, a hidden population's neurons)
    i  <- a_R (i + w z)                               its synapse (dash_syn d_R; w = int8 << the matrix's shift)
    V  <- V - max(V >> 15, sign V) + i                its membrane integrates (dash_mem 15: a leak of one unit)
    n  = min(V // theta_R, 31);  V -= n theta_R       events, the remainder carried (a sigma-delta quantizer)

so ``n[t] ~ (w / theta_R) F(z)[t]`` with ``F(z)[t] = a_R (F[t-1] + z[t])``, its quantization error carried to
the next step. theta_R is the smallest threshold under which a 0/1 train never reaches the cap of 31 (a capped
relay would keep the excess in its membrane and fire on long after its input stopped). The events reach a
target neuron one step later (hidden -> hidden) through its own two synapses: the basis functions
``(F_{a_k} * F_{a_R})(z)`` delayed by one step. The identification (``regression.py``) fits their weights with
the rest; the relays' own registers are fixed here.

Relays are shared: one per channel of each source population, used by every population that source feeds
(and by the source's own recurrence). ``relay_events`` runs them in snncc's bit-exact emulator, so the
identification sees what the chip does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.xylo.chip import CORE

RELAY_DASH_MEM = 15          # V loses max(V >> 15, sign V): one unit per step, an integrator
CURRENT_BUDGET = 3360        # largest chip weight: a channel firing on every step keeps i < 8 w < 32767 (dash <= 3;
                             # halved for each dash above 3, so the current stays in range at every dash)
EVENTS_MAX = 30              # at most 30 events from the current (+1 from the remainder): never the cap of 31, so the
                             # membrane never winds up (a capped relay keeps the excess and fires on long after)
PREFIX = "relay of "
EVENT_CHUNK = 128            # samples whose relay events are computed at once (``relay_events``)


def relay_name(source: str) -> str:
    """The source name of a population's relays (a key of a ``HiddenFloat``'s weights and of the trains)."""
    return PREFIX + source


@dataclass(frozen=True)
class Relay:
    """The relays of one source: ``n`` neurons fed 0/1 events (the input's spikes, single-rule neurons' spikes),
    their synapse dash; ``events_max`` (at most ``EVENTS_MAX``) the events a step the current may ask for (fewer:
    a coarser, different quantization, for the replicas of a network); ``tag`` tells apart the relays of one
    source in different replicas; ``second`` marks a source's second set (another dash), named apart."""

    source: str
    n: int
    dash: int
    events_max: int = EVENTS_MAX
    tag: str = ""
    second: bool = False          # the source's second relay set (``--relays both``: the slower synapse dash)

    def __post_init__(self) -> None:
        if not 1 <= self.events_max <= EVENTS_MAX:
            raise ValueError(f"relay events_max {self.events_max} outside 1..{EVENTS_MAX}")

    @property
    def name(self) -> str:
        """The relays' source name (a key of a ``HiddenFloat``'s weights, of the trains and the layout)."""
        return relay_name(self.source) + self.tag + (f" (dash {self.dash})" if self.second else "")

    def registers(self, shift: int) -> tuple[int, int]:
        """(int8 input weight, threshold) under the input matrix's left ``shift``: the largest weight whose current
        stays in range, and the smallest threshold that can never reach the cap (``current_bound``)."""
        budget = CURRENT_BUDGET >> max(0, int(self.dash) - 3)       # slower dashes hold a larger current
        w8 = int(max(1, min(CORE.weight_max, budget >> int(shift))))
        chip_w = w8 << int(shift)
        theta = -(-current_bound(chip_w, self.dash) // self.events_max)
        return w8, int(min(max(theta, 1), CORE.state_max))

    def gain(self, shift: int) -> float:
        """Events per unit of the filtered train F(z) under ``shift``: (w << shift) / theta_R."""
        w8, theta = self.registers(shift)
        return (w8 << int(shift)) / theta


def current_bound(chip_w: int, dash: int) -> int:
    """The largest current a relay reaches on a 0/1 train (an event every step), under the chip's decay
    i <- i + w, i <- i - max(i >> d, 1): below (w + 1)(2^d - 1)."""
    return (int(chip_w) + 1) * ((1 << int(dash)) - 1)


def relay_events(z: np.ndarray, dash: int, w8: int, shift: int, theta: int) -> np.ndarray:
    """Events (B, T, n) uint8 of relays fed ``z`` (B, T, n) 0/1 events, one channel each, delivered in the step they
    are given: the relays alone, as input-expansion neurons, run by ``emulator.emulate``."""
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    z = np.asarray(z)
    n = z.shape[2]
    w_in = np.zeros((n, n, CORE.hidden_synapse_states), np.int8)
    w_in[np.arange(n), np.arange(n), 0] = w8
    spec = XyloSpec(weights_in=w_in, weights_rec=np.zeros((n, n, CORE.hidden_synapse_states), np.int8),
                    weights_out=np.zeros((n, 1), np.int8), dash_mem=np.full(n, RELAY_DASH_MEM, np.uint8),
                    dash_syn=np.full(n, dash, np.uint8), dash_syn_2=np.full(n, dash, np.uint8),
                    dash_mem_out=np.zeros(1, np.uint8), dash_syn_out=np.ones(1, np.uint8),
                    threshold=np.full(n, theta, np.int16), threshold_out=np.ones(1, np.int16),
                    bias=np.zeros(n, np.int16), bias_out=np.zeros(1, np.int16), weight_shift_in=int(shift),
                    weight_shift_rec=0, weight_shift_out=0, aliases=[[] for _ in range(n)], dt=1.0)
    out = np.zeros(z.shape, np.uint8)
    for s0 in range(0, z.shape[0], EVENT_CHUNK):           # the recorded states of a chunk of samples at a time
        out[s0:s0 + EVENT_CHUNK] = emulate(spec, z[s0:s0 + EVENT_CHUNK].astype(np.uint8), record=True).spikes
    return out
