"""Small IR chains for the Xylo lowering tests (seeded)."""

from __future__ import annotations

import numpy as np

from snncc.ir import LIF, Dense, Graph, Input, Output, Readout, validate


def chain(rng, n_in=6, n_hidden=12, n_out=3, *, alpha=0.75, beta=0.875, alpha_o=0.5, beta_o=0.75, theta=1.0,
          w_scale=0.6, rec_scale=0.3, delays=(0, 1, 0), reset="subtract", dt=1e-3, bias=None):
    """input -> Dense -> LIF (self loop) -> Dense -> LIF -> spike-count readout, Euler decays given exactly
    (tau = dt / (1 - a)); ``delays`` = (input, recurrent, output) IR delays."""
    g = Graph(dt, name="chain")
    g.add("input", Input(n_in))
    g.add("w_in", Dense(rng.normal(0, w_scale, (n_hidden, n_in)) + 0.2))
    g.add("hidden", LIF(n_hidden, dt / (1 - alpha), dt / (1 - beta), theta, reset=reset, discretisation="euler",
                        bias=bias, bias_placement="voltage"))
    g.add("w_rec", Dense(rng.normal(0, rec_scale, (n_hidden, n_hidden))))
    g.add("w_out", Dense(rng.normal(0.1, w_scale, (n_out, n_hidden))))
    g.add("out", LIF(n_out, dt / (1 - alpha_o), dt / (1 - beta_o), theta, reset=reset, discretisation="euler"))
    g.add("readout", Readout(n_out))
    g.add("output", Output(n_out))
    g.connect("input", "w_in", delay=delays[0])
    g.connect("w_in", "hidden")
    g.connect("hidden", "w_rec", delay=delays[1])
    g.connect("w_rec", "hidden")
    g.connect("hidden", "w_out", delay=delays[2])
    g.connect("w_out", "out")
    g.connect("out", "readout")
    g.connect("readout", "output")
    return validate(g)


def spikes(rng, batch=6, steps=80, channels=6, p=0.15) -> np.ndarray:
    return (rng.random((batch, steps, channels)) < p).astype(np.uint8)


def run_xylosim(spec: dict, x: np.ndarray, record: bool = False):
    """A spec dict run in the vendor's simulator (``tests/xylo/oracle.py``): an ``XyloResult``."""
    from snncc.targets.xylo.spec import XyloSpec
    from tests.xylo.oracle import XyloSimOracle

    n = np.asarray(spec["threshold"]).size
    full = {"aliases": [[] for _ in range(n)], "dt": 1e-3, **spec}     # hand-made specs may leave these out
    return XyloSimOracle(XyloSpec(**full)).run(np.asarray(x), record=record)


STUDY_KNOBS = ("calibration", "density", "emulator", "rounding", "refit", "readout")


def lower_with(graph, settings: dict | None = None):
    """``lowering.lower.lower`` with ``settings`` split as the library takes them: the option record validated by
    the target's declarations (as every verb builds it) and the study knobs (``XyloStudyKnobs``)."""
    from snncc.targets.base import target_options
    from snncc.targets.xylo.capabilities import target
    from snncc.targets.xylo.lowering.lower import lower
    from snncc.targets.xylo.options import XyloStudyKnobs

    settings = dict(settings or {})
    knobs = XyloStudyKnobs(**{k: settings.pop(k) for k in list(settings) if k in STUDY_KNOBS})
    return lower(graph, target_options(target, settings, "lower"), knobs)
