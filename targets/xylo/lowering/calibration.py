"""The calibration of a lowering: the float graph's parameters per population and its teacher-forcing traces.

The float graph as deployed runs on the calibration inputs (seeded random spikes, or the inputs a study
gives); per population the lowering keeps its presynaptic and own spike trains, delayed as the IR delivers
them, and its pre-reset voltages (``calibrate``). Every fit (``regression.py``), state limit
(``integers.py``) and relay train (``relay_plan.py``) reads them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit import SnnccError
from snncc.targets.kit.graphs import current_biases
from snncc.targets.xylo.lowering.chip_form import BIAS_SOURCE
from snncc.targets.xylo.lowering.regression import delayed
from snncc.targets.xylo.lowering.structure import Population
from snncc.targets.xylo.lowering.timing import XyloTiming, projection_delay
from snncc.targets.xylo.options import (
    BOTH_CALIBRATION_SAMPLES, DEFAULT_CALIBRATION_SAMPLES, DEFAULT_DENSITY, XyloOptions, XyloStudyKnobs,
)


@dataclass
class Source:
    """Per population: the float graph's parameters and its calibration traces."""

    pop: Population
    alpha: np.ndarray
    beta: np.ndarray
    theta: np.ndarray
    bias_v: np.ndarray
    bias_i: np.ndarray
    w_ff: np.ndarray
    w_rec: np.ndarray | None
    d_ff: int
    bias_lag: int | None = None        # IR step from which the always-on source's spikes arrive (None: not usable)
    trains: dict[str, np.ndarray] = field(default_factory=dict)
    raw: dict[str, np.ndarray] = field(default_factory=dict)      # pre's and own spikes, undelayed (IR time)
    v_pre: np.ndarray | None = None


def sources(g: Graph, pops: list[Population], timing: XyloTiming) -> list[Source]:
    """The source's spikes (chip steps 0, 1, ...) reach every population at chip step 1: IR step 1 - shift."""
    out = []
    for p in pops:
        op = g.node(p.lif)
        alpha, beta = op.decays(g.dt)
        bias_v = op.bias if (op.bias is not None and op.bias_placement == "voltage") else np.zeros(op.n)
        bias_i = np.zeros(op.n)
        for term in current_biases(g, p.lif):
            bias_i = bias_i + term.vector
        out.append(Source(p, np.asarray(alpha, float), np.asarray(beta, float), op.threshold.astype(float),
                          np.asarray(bias_v, float), bias_i, g.node(p.ff).weight,
                          None if p.rec is None else g.node(p.rec).weight, projection_delay(g, p.pre, p.ff, p.lif),
                          1 - timing.shifts[p.lif] if timing.shifts[p.lif] <= 1 else None))
    return out


CALIBRATION_CHUNK = 32       # samples the float graph runs at once while calibrating


def spike_trains(z) -> np.ndarray:
    """0/1 spikes (or small whole event counts) held as uint8: every consumer reads them as float64, unchanged."""
    z = np.asarray(z)
    if z.dtype == np.uint8:
        return z
    out = z.astype(np.uint8)
    if not np.array_equal(out, z):
        raise SnnccError("internal check failed: calibration spike trains that are not whole counts 0 .. 255",
                         field="calibration")
    return out


def calibrate(ref: Graph, srcs: list[Source], x: np.ndarray) -> None:
    """Teacher-forcing traces: each population's delayed presynaptic and own spike trains (uint8), pre-reset
    voltages (float64); the float graph runs ``CALIBRATION_CHUNK`` samples at a time."""
    from snncc.ir.simulate import simulate
    from snncc.targets.kit.compute import one_thread

    b, steps = np.shape(x)[:2]
    spikes = {s.pop.lif: np.zeros((b, steps, s.theta.size), np.uint8) for s in srcs}
    voltage = {s.pop.lif: np.zeros((b, steps, s.theta.size), np.float64) for s in srcs}
    with one_thread():
        for s0 in range(0, b, CALIBRATION_CHUNK):
            res = simulate(ref, x[s0:s0 + CALIBRATION_CHUNK], record="voltage")
            for name in spikes:
                spikes[name][s0:s0 + CALIBRATION_CHUNK] = spike_trains(res.spikes[name])
                voltage[name][s0:s0 + CALIBRATION_CHUNK] = np.asarray(res.voltage[name])
            del res
    trains = {srcs[0].pop.pre: spike_trains(x), **spikes}
    ones = np.ones(np.shape(x)[:2] + (1,), np.uint8)
    for s in srcs:
        s.trains = {s.pop.pre: delayed(trains[s.pop.pre], s.d_ff), s.pop.lif: delayed(trains[s.pop.lif], 1)}
        s.raw = {s.pop.pre: trains[s.pop.pre], s.pop.lif: trains[s.pop.lif]}
        if s.bias_lag is not None:
            s.trains[BIAS_SOURCE] = delayed(ones, s.bias_lag)
        v = voltage[s.pop.lif]
        v += s.theta * trains[s.pop.lif]
        s.v_pre = v


def float_counts(ref: Graph, x: np.ndarray, last: str) -> np.ndarray:
    """The float graph's output spike counts on ``x`` (what a candidate is measured against)."""
    from snncc.ir.simulate import simulate
    from snncc.targets.kit.compute import one_thread

    with one_thread():
        return np.asarray(simulate(ref, x, record="spikes", populations=[last]).spikes[last]).sum(axis=1)


def sample_count(options: XyloOptions) -> int:
    """Seeded calibration samples: ``--calibration-samples``, else 256 (1,024 with ``--relays both``)."""
    return int(options.calibration_samples
               or (BOTH_CALIBRATION_SAMPLES if options.both_relays else DEFAULT_CALIBRATION_SAMPLES))


def calibration_inputs(options: XyloOptions, knobs: XyloStudyKnobs, width: int, steps: int,
                       seed: int | None = None) -> np.ndarray:
    """The calibration inputs: the study's (``knobs.calibration``, as 0/1 spikes) or seeded random spikes of
    ``steps`` steps (the model's time base, ``kit.timebase.sample_steps``; ``seed``, default the options' seed)."""
    given = knobs.calibration
    if given is not None:
        x = np.asarray(given)
        if x.ndim != 3 or x.shape[2] != width:
            raise SnnccError(f"calibration inputs must be (samples, steps, {width})", field="calibration")
        return (x > 0).astype(np.uint8)
    samples = sample_count(options)
    density = float(knobs.density or DEFAULT_DENSITY)
    seed = int(options.seed if seed is None else seed)
    if not 0 < density <= 1:
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    return (np.random.default_rng(seed).random((samples, steps, width)) < density).astype(np.uint8)


def describe(options: XyloOptions, knobs: XyloStudyKnobs, x: np.ndarray) -> str:
    """How the calibration inputs came about (the artefact's record)."""
    if knobs.calibration is not None:
        return f"{x.shape[0]} given spike trains of {x.shape[1]} steps"
    return (f"{x.shape[0]} seeded random spike trains (density {float(knobs.density or DEFAULT_DENSITY):g}, "
            f"seed {int(options.seed)}), {x.shape[1]} steps (SYNTHETIC)")


def own_spikes(s: Source) -> np.ndarray:
    """A population's own spikes, undelayed (its trains hold them delayed by 1)."""
    own = s.trains[s.pop.lif]
    out = np.zeros_like(own)
    out[:, :-1] = own[:, 1:]
    return out
