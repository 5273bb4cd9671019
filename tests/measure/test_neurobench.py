"""snncc's NeuroBench figures of the float graph against the ``neurobench`` package's own (2.3.0), on the same inputs.

The float graph (the NIR paper's subtract-reset Braille RSNN) is built as an snnTorch module whose neurons compute
exactly the IR's update (integrate, fire on V > theta, subtract; a spiking neuron NeuroBench hooks as such), run
step by step by NeuroBench's ``SNNTorchModel``; NeuroBench's ``Benchmark`` measures it. The workload metrics must be
equal; the footprint equals snncc's float32 count once snnTorch's own two bookkeeping scalars per neuron layer
(``graded_spikes_factor``, ``reset_mechanism_val``: not model constants) are set aside."""

from __future__ import annotations

import numpy as np
import pytest

from snncc_test_helpers import require

NIR = "braille_noDelay_noBias_subtract.nir"


def _module(graph, dtype):
    torch = require("torch")
    snn = require("snntorch")

    w_in, w_rec, w_out = (graph.node(n).weight for n in ("fc1", "lif1.w_rec", "fc2"))
    hidden, out = graph.node("lif1.lif"), graph.node("lif2")

    class IRNeuron(snn.SpikingNeuron):
        """The IR's LIF (Euler or exp decays from the graph): I = aI + x; V = bV + I; s = V > theta; V -= theta*s."""

        def __init__(self, op):
            alpha, beta = op.decays(graph.dt)
            super().__init__(threshold=torch.as_tensor(np.broadcast_to(op.threshold, (op.n,)).copy(), dtype=dtype),
                             reset_mechanism=op.reset if op.reset == "subtract" else "zero")
            self.register_buffer("alpha", torch.as_tensor(np.broadcast_to(alpha, (op.n,)).copy(), dtype=dtype))
            self.register_buffer("beta", torch.as_tensor(np.broadcast_to(beta, (op.n,)).copy(), dtype=dtype))
            self.zero = op.reset == "zero"
            self.state = None

        def forward(self, x):
            i, v = self.state if self.state is not None else (torch.zeros_like(x), torch.zeros_like(x))
            i = self.alpha * i + x
            v = self.beta * v + i
            s = (v > self.threshold).to(x.dtype)
            v = v * (1 - s) if self.zero else v - s * self.threshold
            self.state = (i, v)
            return s, v

    class Net(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.fc_in = torch.nn.Linear(w_in.shape[1], w_in.shape[0], bias=False, dtype=dtype)
            self.fc_rec = torch.nn.Linear(w_rec.shape[1], w_rec.shape[0], bias=False, dtype=dtype)
            self.fc_out = torch.nn.Linear(w_out.shape[1], w_out.shape[0], bias=False, dtype=dtype)
            for layer, w in ((self.fc_in, w_in), (self.fc_rec, w_rec), (self.fc_out, w_out)):
                layer.weight.data = torch.as_tensor(w, dtype=dtype)
            self.hidden, self.out = IRNeuron(hidden), IRNeuron(out)
            self.reset()

        def reset(self):
            self.previous = None
            self.hidden.state = self.out.state = None

        def forward(self, x):
            x = x.to(dtype)
            prev = self.previous if self.previous is not None else torch.zeros(x.shape[0], w_rec.shape[1], dtype=dtype)
            s_h, _ = self.hidden(self.fc_in(x) + self.fc_rec(prev))      # the recurrent edge: delay 1
            self.previous = s_h
            return self.out(self.fc_out(s_h))

    return Net()


def test_float_graph_figures_equal_neurobenchs_own(shared_nir):
    torch = require("torch")
    require("snntorch")
    from neurobench.benchmarks import Benchmark
    from neurobench.metrics.static import ConnectionSparsity, Footprint
    from neurobench.metrics.workload import ActivationSparsity, SynapticOperations
    from neurobench.models import SNNTorchModel

    from snncc.frontends import LoadOptions, load_model
    from snncc.ir.simulate import simulate
    from snncc.measure.neurobench import float_figures

    graph = load_model(shared_nir / NIR, LoadOptions(dt=1e-4, reset="subtract"))
    rec = graph.node("lif1.w_rec")         # pruned: a third of the recurrent synapses zero (connection sparsity > 0)
    rec.weight = np.where(np.random.default_rng(5).random(rec.weight.shape) < 1 / 3, 0.0, rec.weight)
    x = (np.random.default_rng(4).random((12, 120, 12)) < 0.1).astype(np.float64)
    ours = float_figures(graph, x)
    net = _module(graph, torch.float64)
    # the module is the IR: equal spikes on these inputs (else the comparison would compare other runs)
    model = SNNTorchModel(net)
    got = model(torch.as_tensor(x)).numpy()
    assert np.array_equal(got, simulate(graph, x, record="spikes").spikes["lif2"]) and got.sum() > 0

    from torch.utils.data import DataLoader, TensorDataset

    loader = DataLoader(TensorDataset(torch.as_tensor(x), torch.zeros(len(x), dtype=torch.long)), batch_size=6)
    workload = Benchmark(SNNTorchModel(_module(graph, torch.float64)), loader, [], [],
                         [[ConnectionSparsity], [ActivationSparsity, SynapticOperations]]).run()
    assert workload["SynapticOperations"] == pytest.approx(ours.synaptic_operations, rel=1e-12)
    assert workload["ActivationSparsity"] == pytest.approx(ours.activation_sparsity, rel=1e-12)
    assert workload["ConnectionSparsity"] == pytest.approx(ours.connection_sparsity, abs=5e-4)    # 3 decimals
    assert 0.1 < ours.connection_sparsity < 0.3 and ours.synaptic_operations["Effective_ACs"] > 0

    float32 = _module(graph, torch.float32)
    static = Benchmark(SNNTorchModel(float32), loader, [], [], [[Footprint], []]).run()
    bookkeeping = sum(b.numel() * b.element_size() for name, b in float32.named_buffers()
                      if name.split(".")[-1] in ("graded_spikes_factor", "reset_mechanism_val"))
    assert static["Footprint"] - bookkeeping == ours.footprint


def test_a_layer_behind_a_pooling_counts_as_neurobench_counts_it():
    """A synaptic layer fed through a sum pooling sees graded sums: NeuroBench's own per-call rule (MACs where the
    call's input is not all 0/±1, else ACs), called per sample and step, gives what snncc's tally gives."""
    torch = require("torch")
    from neurobench.metrics.utils.layers.macs import single_layer_MACs

    from snncc.measure.neurobench import Projection, Tally

    rng = np.random.default_rng(0)
    x = (rng.random((3, 20, 8)) < 0.2).astype(np.float64)                  # spikes of an 8-neuron population
    pool = np.kron(np.eye(4), np.ones((1, 2)))                               # sum pooling, pairs: (4, 8)
    weight = np.where(rng.random((3, 4)) < 0.3, 0.0, rng.normal(size=(3, 4)))
    tally = Tally([Projection("pop", "dense", weight, 0, pool)], [])
    tally.add({"pop": x})
    layer = torch.nn.Linear(4, 3, bias=False, dtype=torch.float64)
    layer.weight.data = torch.as_tensor(weight)
    ac = mac = 0
    for b in range(x.shape[0]):
        for t in range(x.shape[1]):
            ops, spiking = single_layer_MACs(torch.as_tensor(pool @ x[b, t])[None], layer)
            ac, mac = (ac + ops, mac) if spiking else (ac, mac + ops)
    got = tally.synaptic_operations()
    assert mac > 0 and ac > 0                                               # both kinds occur on these inputs
    assert got["Effective_ACs"] * 3 == ac and got["Effective_MACs"] * 3 == mac
    assert got["Dense"] == 3 * 4 * 20
