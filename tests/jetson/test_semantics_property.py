"""Property test: for random small graphs (delays, refractory periods, resets, biases, Euler or
exp decays, recurrent or not, spike-count or voltage readout) the torch modules the exports are
traced from compute what the IR reference computes (float32 both, eager torch, no export)."""

from __future__ import annotations

import numpy as np
import torch
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.ir.simulate import simulate
from snncc.ir.validate import validate
from snncc.targets.jetson.plan import plan_graph
from snncc.targets.jetson.torch_graph import StepModel, UnrolledModel, run_steps


@st.composite
def graphs(draw):
    seed = draw(st.integers(0, 2**16))
    rng = np.random.default_rng(seed)
    n_in, n_a, n_b = 3, draw(st.integers(2, 6)), 2
    g = Graph(0.001, name="prop")

    def lif(n, spiking=True):
        reset = draw(st.sampled_from(["zero", "subtract"])) if spiking else "zero"
        bias = draw(st.sampled_from([None, "current", "voltage"]))
        return LIF(n=n, tau_syn=rng.uniform(0.002, 0.01, n), tau_mem=rng.uniform(0.005, 0.05, n),
                   threshold=rng.uniform(0.3, 1.0, n) if spiking else np.inf, reset=reset,
                   refractory=draw(st.integers(1, 4)), discretisation=draw(st.sampled_from(["exp", "euler"])),
                   bias=None if bias is None else rng.normal(0, 0.1, n), bias_placement=bias or "current")

    voltage_readout = draw(st.booleans())
    g.add("input", Input(width=n_in))
    g.add("w_in", Dense(weight=rng.normal(0, 2.0, (n_a, n_in)),
                        bias=rng.normal(0, 0.2, n_a) if draw(st.booleans()) else None))
    g.add("a", lif(n_a))
    g.add("w_out", Dense(weight=rng.normal(0, 2.0, (n_b, n_a))))
    g.add("b", lif(n_b, spiking=not voltage_readout))
    g.add("readout", Readout(width=n_b, mode="membrane_max" if voltage_readout else "spike_count"))
    g.add("output", Output(width=n_b))
    g.connect("input", "w_in", delay=draw(st.integers(0, 3)))
    g.connect("w_in", "a")
    if draw(st.booleans()):
        g.add("w_rec", Dense(weight=rng.normal(0, 1.0, (n_a, n_a))))
        g.connect("a", "w_rec", delay=draw(st.integers(1, 3)))
        g.connect("w_rec", "a")
    g.connect("a", "w_out", delay=draw(st.integers(0, 3)))
    g.connect("w_out", "b")
    g.connect("b", "readout", port="voltage" if voltage_readout else "spikes")
    g.connect("readout", "output")
    return validate(g), seed


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(graphs())
def test_torch_modules_match_the_reference(case):
    g, seed = case
    steps = 20
    x = (np.random.default_rng(seed + 1).random((3, steps, 3)) < 0.4).astype(np.float32)
    ref = np.asarray(simulate(g, x, dtype=torch.float32).output)
    plan = plan_graph(g)
    with torch.no_grad():
        _, seq = UnrolledModel(plan, steps)(torch.as_tensor(x))
        stepped = run_steps(StepModel(plan), torch.as_tensor(x))
    for got in (seq.numpy(), stepped.numpy()):
        if plan.spiking_output:
            assert np.mean(got == ref) >= 0.995  # exact in practice (150 examples checked)
        else:
            np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-5)
