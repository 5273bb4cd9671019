"""Does a Xylo network run in real time: core clock cycles per time step against ``dt`` (an ESTIMATE).

``cycles_per_step`` counts the cycles one step needs from per-operation costs SynSense published for Xylo
Audio 2 (Rockpool 3.1's cycles model), in the worst case (every channel and neuron active) and at event
rates (``event_rates``: measured in snncc's emulator); ``real_time`` compares them with ``dt`` at the HDK's
fastest core clock. Not a measurement: no board was available.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np


# Cycle costs of the Audio 2 core per operation, as published by SynSense in Rockpool 3.1's Audio 2 cycles
# model (syns61201/power_cycles_model.py); the model below is snncc's own: an ESTIMATE, not a measurement.
CYCLES_INPUT_EVENT_PER_NEURON = 3.5   # an input event scans the input-expansion neurons' weights
CYCLES_INPUT_CHANNEL = 1
CYCLES_HIDDEN_SYNAPSE_EVENT = 7       # a hidden spike, per recurrent synapse it reaches
CYCLES_HIDDEN_NEURON_ISYN = 3
CYCLES_OUTPUT_SYNAPSE_EVENT = 8       # a hidden spike, per output neuron
CYCLES_OUTPUT_SCAN = 1
CYCLES_HIDDEN_NEURON = 19             # each hidden neuron's update
CYCLES_HIDDEN_SPIKE = 3               # extra work of a spiking hidden neuron
CYCLES_OUTPUT_NEURON = 12
CORE_CLOCK_MAX_HZ = 50e6              # the Audio 2 HDK's core clock: 100 MHz / 2 at the fastest setting


@dataclass
class RealTime:
    cycles_worst: float          # every input channel, hidden and output neuron active every step
    cycles_expected: float       # at the given (or measured) event rates
    clock_hz: float
    dt: float
    rates: dict[str, float]

    @property
    def step_time_worst(self) -> float:
        return self.cycles_worst / self.clock_hz

    @property
    def real_time(self) -> bool:
        """In real time even in the worst case (every channel and neuron active every step)."""
        return self.step_time_worst <= self.dt

    @property
    def step_time_expected(self) -> float:
        return self.cycles_expected / self.clock_hz

    @property
    def real_time_expected(self) -> bool:
        """In real time at the event rates (the load expected)."""
        return self.step_time_expected <= self.dt

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(step_time_worst_s=self.step_time_worst, real_time=self.real_time,
                 margin=self.dt / self.step_time_worst if self.step_time_worst else math.inf,
                 step_time_expected_s=self.step_time_expected, real_time_expected=self.real_time_expected,
                 margin_expected=(self.dt * self.clock_hz / self.cycles_expected if self.cycles_expected
                                  else math.inf),
                 note="ESTIMATE from per-operation cycle costs (SynSense, Rockpool 3.1 Audio 2 model); not measured")
        return d

    def line(self, rates_from: str = "the given inputs") -> str:
        return verdict(self.as_dict(), rates_from)


def verdict(rt: dict[str, Any], rates_from: str) -> str:
    """The real-time verdict of a ``RealTime.as_dict()``: at the expected load first (the event rates of
    ``rates_from``), the worst case beside it."""
    at_rates = rt.get("real_time_expected")
    if at_rates is None:                       # a record of an older snncc: judge the expected load from its figures
        at_rates = rt["margin_expected"] >= 1.0
    clock = rt["clock_hz"]
    return (f"at the event rates of {rates_from}: {'runs in real time' if at_rates else 'does NOT run in real time'}, "
            f"{rt['cycles_expected']:,.0f} core cycles per step ({rt['cycles_expected'] / clock * 1e6:.1f} us at "
            f"{clock / 1e6:g} MHz) against dt = {rt['dt'] * 1e6:g} us, margin {rt['margin_expected']:.2f}x; worst case "
            f"(every channel and neuron active every step): {rt['cycles_worst']:,.0f} cycles "
            f"({rt['step_time_worst_s'] * 1e6:.1f} us), margin {rt['margin']:.2f}x"
            + ("" if rt["real_time"] else ", not real time") + " (ESTIMATE, not measured)")


def cycles_per_step(spec: dict, input_rate: float = 1.0, hidden_rate: float = 1.0, output_rate: float = 1.0) -> float:
    """Core cycles one step needs: input events scan the input-expansion neurons, each hidden spike its
    recurrent fan-out and the output neurons, then every hidden and output neuron updates. Rates are the
    probabilities that a channel / neuron has an event in a step (1: worst case)."""
    get = spec.__getitem__ if isinstance(spec, dict) else lambda k: getattr(spec, k)   # a dict or an XyloSpec
    w_in = np.asarray(get("weights_in"))
    w_rec = np.asarray(get("weights_rec"))
    w_rec = w_rec if w_rec.ndim == 3 else w_rec[:, :, None]
    n_in, n_ien = w_in.shape[:2]
    n = w_rec.shape[0]
    n_out = np.asarray(get("weights_out")).shape[1]
    fanout = float(np.mean(np.count_nonzero(w_rec.reshape(n, n, -1).any(axis=2), axis=1))) if n else 0.0
    inputs = n_in * (input_rate * n_ien * CYCLES_INPUT_EVENT_PER_NEURON + CYCLES_INPUT_CHANNEL)
    recurrent = n * (hidden_rate * fanout * CYCLES_HIDDEN_SYNAPSE_EVENT + CYCLES_HIDDEN_NEURON_ISYN)
    to_output = n * hidden_rate * (CYCLES_OUTPUT_SCAN + n_out * CYCLES_OUTPUT_SYNAPSE_EVENT)
    neurons = n * (CYCLES_HIDDEN_NEURON + hidden_rate * CYCLES_HIDDEN_SPIKE) + n_out * CYCLES_OUTPUT_NEURON
    return float(inputs + recurrent + to_output + neurons)


def real_time(spec: dict, dt: float, rates: dict[str, float] | None = None,
              clock_hz: float = CORE_CLOCK_MAX_HZ) -> RealTime:
    """Worst-case and expected cycles per step against ``dt`` at ``clock_hz``."""
    r = {"input": 1.0, "hidden": 1.0, "output": 1.0, **(rates or {})}
    return RealTime(cycles_per_step(spec), cycles_per_step(spec, r["input"], r["hidden"], r["output"]),
                    float(clock_hz), float(dt), r)


RATE_CHUNK = 64     # samples emulated at once while counting event rates (their recorded states stay small)


def event_rates(spec: dict, chip_x: np.ndarray) -> dict[str, float]:
    """The share of channel- and neuron-steps with an event, ``spec`` run on the chip inputs ``chip_x`` (every
    hidden neuron: relays and copies too); several events of one neuron in one step count once, as the cycle
    model states its rates (``cycles_per_step``). The samples run ``RATE_CHUNK`` at a time (exact counts)."""
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    spec = spec if isinstance(spec, XyloSpec) else XyloSpec(**spec)
    hidden = output = 0
    for s0 in range(0, chip_x.shape[0], RATE_CHUNK):
        run = emulate(spec, chip_x[s0:s0 + RATE_CHUNK], record=True)
        hidden += int(np.count_nonzero(run.spikes))
        output += int(np.count_nonzero(run.output_spikes))
    b, t = chip_x.shape[:2]
    return {"input": float(np.mean(chip_x > 0)), "hidden": hidden / (b * t * spec.n_hidden),
            "output": output / (b * t * spec.n_out)}
