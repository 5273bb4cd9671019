"""The generated C, compiled by the host gcc (-O2 -std=c99 -Wall -Wextra -Werror -pedantic), equals the emulator
spike for spike and state for state (every population's spikes, current and voltage at every step): on random
graphs (sizes, delays, both resets, refractory periods, spike rules, biases, saturating inputs) and on every NIR
graph of the test data the target takes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from c_test_graphs import NIR_DIR, assert_trace_equal, need, network, random_graph, sources, spikes


def host_run(net, x, cache):   # noqa: ANN001
    from snncc.targets.c.toolchain import build as tb
    from snncc.targets.c.toolchain import commands as cmd

    built = tb.build(sources(net), cmd.host_command(trace=True), cmd.HOST_PROGRAM, cache=cache)
    return tb.run_program(built.path, x, net.outputs, sizes=[p.n for p in net.populations])


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10_000), n_in=st.integers(1, 9), n_hidden=st.integers(1, 12), n_out=st.integers(1, 5),
       rule=st.sampled_from(["per-layer", "per-neuron", "per-layer-16", "per-neuron-16"]), big=st.booleans(),
       spikes_per_step=st.sampled_from([1, 1, 3]), density=st.sampled_from([0.05, 0.3, 1.0]))
def test_random_graphs_host_c_equals_emulator(build_cache, seed, n_in, n_hidden, n_out, rule, big, spikes_per_step,
                                              density):
    need("gcc")
    from snncc.targets.c.emulation.emulator import emulate_network

    graph = random_graph(seed, n_in=n_in, n_hidden=n_hidden, n_out=n_out, big=big, spikes=spikes_per_step)
    net = network(graph, rule, steps=30)
    x = spikes(3, 30, n_in, density, seed)
    emulated = emulate_network(net, x, record=True)
    ran = host_run(net, x, build_cache)
    np.testing.assert_array_equal(ran.output_spikes, emulated.output_spikes)
    assert_trace_equal(net, emulated, ran.trace)


def test_saturation_is_reached_and_still_equal(build_cache):
    """Weights thousands of thresholds and every input spiking: the int32 clamp is hit, C and emulator agree."""
    need("gcc")
    from snncc.targets.c.emulation.emulator import emulate_network

    graph = random_graph(3, n_in=6, n_hidden=8, n_out=3, big=True, delays=(0, 1))
    net = network(graph, "per-neuron", steps=25)
    x = np.ones((2, 25, 6), np.uint8)
    emulated = emulate_network(net, x, record=True)
    assert sum(emulated.saturated.values()) > 0
    ran = host_run(net, x, build_cache)
    assert_trace_equal(net, emulated, ran.trace)


NIR_GRAPHS = [("braille_noDelay_noBias_subtract.nir", "subtract", "per-neuron"),
              ("braille_noDelay_noBias_subtract.nir", "subtract", "per-layer-16"),
              ("braille_zero_2023.nir", None, "per-neuron-16"),
              ("lif_norse.nir", None, "per-neuron"),
              ("lif_rockpool.nir", None, "per-layer"),
              ("two_lif_neurons.nir", None, "per-neuron")]


@pytest.mark.parametrize("name,reset,rule", NIR_GRAPHS)
def test_nir_graphs_host_c_equals_emulator(build_cache, name, reset, rule):
    need("gcc")
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.c.emulation.emulator import emulate_network

    graph = load_model(NIR_DIR / name, LoadOptions(dt=1e-4, reset=reset))
    net = network(graph, rule, steps=60)
    x = spikes(4, 60, net.inputs, 0.3 if net.inputs == 1 else 0.08, 1)
    emulated = emulate_network(net, x, record=True)
    ran = host_run(net, x, build_cache)
    np.testing.assert_array_equal(ran.output_spikes, emulated.output_spikes)
    assert_trace_equal(net, emulated, ran.trace)
    if name.startswith("braille"):
        assert emulated.counts.sum() > 0       # the comparison is not between two silent runs


def test_conv_graph_host_c_equals_emulator(build_cache):
    """The NIR paper's Sinabs CNN (Conv2d, IF, SumPool2d, Affine): convolutions as sparse fan-out rows."""
    need("gcc")
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.c.emulation.emulator import emulate_network

    graph = load_model(NIR_DIR / "cnn_sinabs.nir", LoadOptions())
    net = network(graph, "per-layer", steps=12)
    assert any(q.layout == "sparse" for q in net.projections)
    x = spikes(2, 12, net.inputs, 0.2, 2)
    emulated = emulate_network(net, x, record=True)
    ran = host_run(net, x, build_cache)
    np.testing.assert_array_equal(ran.output_spikes, emulated.output_spikes)
    assert_trace_equal(net, emulated, ran.trace)
    assert sum(int(s.sum()) for s in emulated.spikes.values()) > 0
