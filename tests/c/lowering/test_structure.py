"""The lowering states the IR's semantics as they are: paths through linear nodes (Dense and Conv chains, a LIF
feeding a LIF directly), their delays summed, a linear node's bias arriving from the step its delays say, current
and voltage biases, both resets, refractory periods. Checked where quantization is exact (dyadic weights,
thresholds, biases and decays): the emulator's integer voltages equal the IR reference's, times 2**F, and so do
the spikes. And what the target cannot express is refused in one line naming the node."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, LSTM, Dense, Input, Output, Readout

from c_test_graphs import exact_graph

DT = 1e-3

def test_emulator_equals_the_ir_reference_where_quantization_is_exact():
    from snncc.ir.simulate import simulate
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.lowering.quantize import quantize
    from snncc.targets.c.lowering.structure import structure

    graph = exact_graph()
    st = structure(graph)
    assert [(q.source, q.target, q.delay) for q in st.projections] == [(-1, 0, 1), (-1, 1, 3), (0, 1, 1), (0, 2, 2),
                                                                        (1, 1, 1), (1, 2, 0)]
    assert [start for start, _ in st.populations[1].bias_i] == [1, 3]      # dense2's bias from step 1, dense1's from 3
    net = quantize(st, "per-neuron-16", 8)
    x = (np.random.default_rng(1).random((6, 8, 16)) < 0.4).astype(np.uint8)
    em = emulate_network(net, x, record=True)
    ref = simulate(graph, x.astype(np.float64), record="all")

    def values(series):   # noqa: ANN001, ANN202 (the reference's arrays: numpy, or torch tensors)
        return np.asarray(series.numpy() if hasattr(series, "numpy") else series, np.float64)

    for p in net.populations:
        np.testing.assert_array_equal(em.spikes[p.name], values(ref.spikes[p.name]).astype(np.uint8), err_msg=p.name)
        np.testing.assert_array_equal(em.voltage[p.name], values(ref.voltage[p.name]) * 2.0 ** p.frac_bits,
                                      err_msg=p.name)
        np.testing.assert_array_equal(em.current[p.name], values(ref.current[p.name]) * 2.0 ** p.frac_bits,
                                      err_msg=p.name)
    assert em.counts.sum() > 0 and all(em.spikes[p.name].any() for p in net.populations)


def _graph(*extra_nodes, edges=(), readout="spike_count", signal="spikes"):
    g = Graph(dt=DT, name="refused")
    g.add("input", Input(width=2, signal=signal))
    g.add("w", Dense(weight=np.ones((2, 2))))
    g.add("lif", LIF(n=2, tau_syn=0.01, tau_mem=0.01, threshold=1.0))
    for name, node in extra_nodes:
        g.add(name, node)
    g.add("readout", Readout(width=2, mode=readout))
    g.add("output", Output(width=2))
    for u, v, *port in (("input", "w"), ("w", "lif"), ("lif", "readout"), ("readout", "output"), *edges):
        g.connect(u, v, port=port[0] if port else "spikes")
    return g


@pytest.mark.parametrize("graph,field,words", [
    (lambda: _graph(readout="membrane_max"), "node 'readout'", "spike counts"),
    (lambda: _graph(signal="analog"), "node 'input'", "analog"),
    (lambda: _graph(("lstm", LSTM(weight_ih=np.zeros((8, 2)), weight_hh=np.zeros((8, 2)))),
                    ("w2", Dense(weight=np.ones((2, 2)))), edges=(("input", "lstm"), ("lstm", "w2"), ("w2", "lif"))),
     "node 'lstm'", "LSTM"),
    (lambda: _graph(("w2", Dense(weight=np.ones((2, 2)))), edges=(("lif", "w2", "voltage"),)), "edge lif->w2",
     "voltage"),
])
def test_refusals_name_the_node_and_why(graph, field, words):
    from snncc.errors import SnnccError
    from snncc.targets.c.lowering.structure import structure

    with pytest.raises(SnnccError) as err:
        structure(graph())
    assert err.value.field == field and words in str(err.value)
