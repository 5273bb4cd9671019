"""Graphs and helpers the C target's tests share: seeded random IR graphs of every feature the target runs,
the artefact's sources for a network, and the toolchain gate (skip outside CI, fail in CI)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.ir.validate import validate

NIR_DIR = Path(__file__).resolve().parents[1] / "data" / "nir"
IN_CI = os.environ.get("CI") == "true"


def need(*tools: str) -> None:
    """Skip (outside CI) or fail (CI=true: the tools are installed by .ci/run) when a tool is missing."""
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        text = f"{', '.join(missing)} not installed (Debian: gcc, gcc-arm-none-eabi, libnewlib-arm-none-eabi, " \
               "qemu-system-arm)"
        if IN_CI:
            pytest.fail(text + "; CI must install them (.ci/run)")
        pytest.skip(text)


def random_graph(seed: int, *, n_in: int = 5, n_hidden: int = 6, n_out: int = 3, delays=(0, 1, 2),
                 resets=("zero", "subtract"), big: bool = False, spikes: int = 1, biases: bool = True,
                 dt: float = 1e-3) -> Graph:
    """A seeded recurrent graph: input -> Dense (delay d0) -> hidden LIF <-> Dense (delay >= 1) ; hidden -> Dense
    (delay d2) -> output LIF, with random time constants, discretisation, refractory, thresholds per neuron,
    biases (Dense biases on the current, a voltage bias), spike rule; ``big``: weights thousands of thresholds
    (the int32 state saturates)."""
    rng = np.random.default_rng(seed)
    scale = 4000.0 if big else 1.0
    g = Graph(dt=dt, name=f"random{seed}")
    g.add("input", Input(width=n_in))
    disc = str(rng.choice(["exp", "euler"]))

    def lif(n: int, reset: str) -> LIF:
        tau_syn = rng.uniform(2 * dt, 20 * dt, n)
        tau_mem = rng.uniform(2 * dt, 40 * dt, n)
        theta = rng.uniform(0.5, 1.5, n)
        bias = rng.normal(0, 0.05, n) if biases and rng.random() < 0.5 else None
        return LIF(n=n, tau_syn=tau_syn, tau_mem=tau_mem, threshold=theta, reset=reset,
                   refractory=int(rng.integers(1, 4)), discretisation=disc, bias=bias,
                   bias_placement=str(rng.choice(["current", "voltage"])),
                   max_spikes=int(rng.integers(1, spikes + 1)), fire_test=str(rng.choice([">", ">="])))

    g.add("w_in", Dense(weight=rng.normal(0, 1.2, (n_hidden, n_in)) * scale,
                        bias=rng.normal(0, 0.1, n_hidden) if biases and rng.random() < 0.5 else None))
    g.add("hidden", lif(n_hidden, str(rng.choice(resets))))
    g.add("w_rec", Dense(weight=rng.normal(0, 0.4, (n_hidden, n_hidden)) * scale,
                         bias=rng.normal(0, 0.05, n_hidden) if biases and rng.random() < 0.3 else None))
    g.add("w_out", Dense(weight=rng.normal(0, 1.0, (n_out, n_hidden)) * scale))
    g.add("out", lif(n_out, str(rng.choice(resets))))
    g.add("readout", Readout(width=n_out))
    g.add("output", Output(width=n_out))
    d = [int(rng.choice(delays)) for _ in range(3)]
    g.connect("input", "w_in", delay=d[0])
    g.connect("w_in", "hidden", delay=0)
    g.connect("hidden", "w_rec", delay=max(1, d[1]))
    g.connect("w_rec", "hidden", delay=0)
    g.connect("hidden", "w_out", delay=d[2])
    g.connect("w_out", "out", delay=int(rng.choice(delays)))
    g.connect("out", "readout")
    g.connect("readout", "output")
    return validate(g)


def spikes(samples: int, steps: int, width: int, density: float, seed: int) -> np.ndarray:
    return (np.random.default_rng(seed).random((samples, steps, width)) < density).astype(np.uint8)


def network(graph: Graph, rule: str = "per-neuron", steps: int = 40):
    from snncc.targets.c.lowering.quantize import quantize
    from snncc.targets.c.lowering.structure import structure

    return quantize(structure(graph), rule, steps)


def sources(net) -> dict[str, bytes]:   # noqa: ANN001
    """The C sources and board files of ``net``'s artefact, as written."""
    from snncc.targets.c.artefact import csource, support

    return {"snn.c": csource.source(net, {}).encode(), "snn.h": csource.header(net, {}).encode(),
            "main.c": support.MAIN_C.encode(), "startup_mps2.c": support.STARTUP_C.encode(),
            "mps2_an386.ld": support.LINKER_SCRIPT.encode()}


def assert_trace_equal(net, emulated, trace) -> None:   # noqa: ANN001
    """Every population's spikes, current and voltage of a C trace equal the emulator's."""
    for p, got in zip(net.populations, trace):
        for kind, table in (("spikes", emulated.spikes), ("current", emulated.current), ("voltage", emulated.voltage)):
            np.testing.assert_array_equal(got[kind], table[p.name].astype(np.int64), err_msg=f"{p.name} {kind}")
