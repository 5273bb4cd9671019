"""Graphs and helpers the C target's tests share: seeded random IR graphs of every feature the target runs,
the artefact's sources for a network, and the toolchain gate (skip outside CI, fail in CI)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Conv, Dense, Input, Output, Readout
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


EXACT_DT = 1e-3


def dyadic(rng, shape, step=0.25, most=6):
    return rng.integers(-most, most + 1, shape) * step


def exact_graph() -> Graph:
    """A graph of every structure feature whose parameters the integer grid holds exactly (dyadic weights, thresholds
    and biases; Euler decays 0.5 and 0.75): over 8 steps the emulator equals the IR reference times 2**F."""
    rng = np.random.default_rng(0)
    g = Graph(dt=EXACT_DT, name="exact")
    g.add("input", Input(width=16))
    # input (1 x 4 x 4) -> conv 2 channels 3x3 pad 1 -> sum pool 2x2 -> lif_a (2 x 2 x 2 = 8)
    g.add("conv", Conv(weight=dyadic(rng, (2, 1, 3, 3)), in_shape=(1, 4, 4), stride=1, padding=1))
    g.add("pool", Conv(weight=np.ones((2, 1, 2, 2)), in_shape=(2, 4, 4), stride=2, groups=2))
    g.add("lif_a", LIF(n=8, tau_syn=2 * EXACT_DT, tau_mem=4 * EXACT_DT, threshold=1.0, reset="subtract", refractory=2,
                       discretisation="euler"))
    # input -> dense1 (bias, delay 2 after it) -> dense2 (bias) -> lif_b ; lif_a -> lif_b directly is not the same
    # width, so lif_a -> dense3 (delay 1) -> lif_b, and lif_b <- lif_b recurrent through dense4 (delay 1)
    g.add("dense1", Dense(weight=dyadic(rng, (6, 16)), bias=dyadic(rng, 6, 0.125, 2)))
    g.add("dense2", Dense(weight=dyadic(rng, (8, 6)), bias=dyadic(rng, 8, 0.125, 2)))
    g.add("dense3", Dense(weight=dyadic(rng, (8, 8))))
    g.add("dense4", Dense(weight=dyadic(rng, (8, 8), 0.125)))
    g.add("lif_b", LIF(n=8, tau_syn=2 * EXACT_DT, tau_mem=4 * EXACT_DT, threshold=np.where(np.arange(8) % 2, 1.0, 0.5),
                       reset="zero", refractory=1, discretisation="euler", bias=dyadic(rng, 8, 0.125, 2),
                       bias_placement="voltage"))
    g.add("lif_c", LIF(n=8, tau_syn=2 * EXACT_DT, tau_mem=4 * EXACT_DT, threshold=1.0, reset="subtract",
                       discretisation="euler",
                       bias=np.full(8, 0.25), bias_placement="current", max_spikes=3, fire_test=">="))
    g.add("readout", Readout(width=8))
    g.add("output", Output(width=8))
    for u, v, d in (("input", "conv", 0), ("conv", "pool", 1), ("pool", "lif_a", 0), ("input", "dense1", 0),
                    ("dense1", "dense2", 2), ("dense2", "lif_b", 1), ("lif_a", "dense3", 1), ("dense3", "lif_b", 0),
                    ("lif_b", "dense4", 1), ("dense4", "lif_b", 0), ("lif_b", "lif_c", 0), ("lif_a", "lif_c", 2),
                    ("lif_c", "readout", 0), ("readout", "output", 0)):
        g.connect(u, v, delay=d)
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
