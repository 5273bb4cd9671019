"""Which sigma-delta relays a relayed candidate places (``relay_plan``), and the events they give each
population it feeds, in that population's IR time (``relay_trains``). The relay neuron itself:
``sigma_delta.py``."""

from __future__ import annotations

import numpy as np

from snncc.targets.xylo.lowering import sigma_delta
from snncc.targets.xylo.lowering.calibration import Source
from snncc.targets.xylo.lowering.chip_form import HiddenFloat
from snncc.targets.xylo.lowering.regression import delayed
from snncc.targets.xylo.lowering.timing import CHIP_DELAY_HIDDEN, CHIP_DELAY_INPUT, XyloTiming

PROVISIONAL_SHIFTS = (0, 0)   # the input and recurrent shifts the relays' events are first computed under


def relay_plan(hidden: list[Source], pairs: list[tuple[int, int]] | None,
               events_max: int = sigma_delta.EVENTS_MAX, both: bool = False) -> list[sigma_delta.Relay]:
    """The relays a relayed candidate adds to the populations on ``hidden`` neurons: one per channel of the
    input and of every hidden population that feeds a hidden population (its own recurrence or the next one);
    each takes the *faster* synapse dash of the first population it feeds: relayed through the slower one, its
    events give the cascade a_fast then a_slow, the shape of a CUBA neuron's kernel (the current's decay, then
    the membrane's). Measured on the Braille RSNN over three calibration seeds: 0.822 agreement on random inputs,
    0.914 on the Braille letters, against 0.804 / 0.894 with the slower dash.

    ``both`` (``--relays both``): every source gets a second relay set at the *slower* dash too, so each target
    sees the cascades of both grid poles: the basis a^n, n a^n, b^n, n b^n (two of each pole). On the Braille
    RSNN's kernels (poles 0.75 and 0.85) the least-squares error of the kernel falls from 2 % to 0.2 %; the fit
    has twice the relay columns and needs more calibration (``options.BOTH_CALIBRATION_SAMPLES``)."""
    def relays_of(source: str, width: int, fed: int) -> list[sigma_delta.Relay]:
        """``source``'s relay sets at the dashes of population ``fed`` (the faster; with ``both`` the slower too)."""
        pair = tuple(int(v) for v in pairs[fed]) if pairs is not None else (2, 3)
        dashes = pair[:2] if both and pair[0] != pair[1] else pair[:1]
        return [sigma_delta.Relay(source, width, d, events_max, second=i > 0) for i, d in enumerate(dashes)]

    plan = []
    for k, s in enumerate(hidden):
        if k == 0:
            plan += relays_of(s.pop.pre, s.raw[s.pop.pre].shape[2], 0)
        if s.pop.rec is not None or k + 1 < len(hidden):
            plan += relays_of(s.pop.lif, s.raw[s.pop.lif].shape[2], k if s.pop.rec is not None else k + 1)
    return plan


def relay_trains(hidden: list[Source], plan: list[sigma_delta.Relay], timing: XyloTiming,
                 shifts: tuple[int, int] | None) -> None:
    """Each hidden population's relay trains in its IR time: relay events of source Q (chip rules, the registers
    under ``shifts``, else ``PROVISIONAL_SHIFTS``) reach population P ``d + 1 + s_Q - s_P`` steps after Q's IR
    step (d: Q -> relay, 0 from the input, 1 from hidden neurons; relay -> P: 1)."""
    first_pre = hidden[0].pop.pre
    events: dict[str, np.ndarray] = {}          # each relay set run once, whichever populations it reaches
    for s in hidden:
        for r in plan:
            if r.source not in (s.pop.pre, s.pop.lif if s.pop.rec is not None else None):
                continue
            is_input = r.source == first_pre
            if r.name not in events:
                shift = (shifts or PROVISIONAL_SHIFTS)[0 if is_input else 1]
                w8, theta = r.registers(shift)
                events[r.name] = sigma_delta.relay_events(s.raw[r.source], r.dash, w8, shift, theta).astype(np.uint8)
            lag = (CHIP_DELAY_INPUT if is_input else CHIP_DELAY_HIDDEN) + CHIP_DELAY_HIDDEN \
                + timing.shifts[r.source] - timing.shifts[s.pop.lif]
            s.trains[r.name] = delayed(events[r.name], lag)


def with_relays(pop: HiddenFloat, s: Source, plan: list[sigma_delta.Relay]) -> HiddenFloat:
    """``pop`` with its prior weights at zero and a zero prior for each relay source that reaches it (the
    identification fits them all)."""
    pop.weights = {k: np.zeros_like(v) for k, v in pop.weights.items()}
    for r in plan:
        if r.name in s.trains:
            pop.weights[r.name] = np.zeros((2, pop.n, r.n))
    pop.columns = [(src, k) for k in range(2) for src in pop.weights]
    return pop
