"""Convolutional NIR graphs: the Sinabs N-MNIST CNN of the NIR paper (tests/data/nir, BSD-3-Clause, see
its README) and a small CNN with strides, padding, groups and dilation, through the IR, the Jetson
ONNX artefact and the Loihi bundle.

Inputs are seeded random spike frames shaped like N-MNIST (2 x 34 x 34), not N-MNIST recordings.
"""

from pathlib import Path

import nir
import numpy as np
import onnxruntime as ort
import pytest
import torch
from torch.nn import functional as F

from nir_graphs import run_cli
from snncc.frontends import LoadOptions, load_model
from snncc.ir.nodes import LIF, Conv
from snncc.ir.simulate import simulate
from snncc.targets.loihi import lower_model
from snncc.targets.loihi.bundle.read import read_bundle
from snncc.targets.loihi.emulation.emulator import emulate
from snncc.targets.loihi.checks.exactness import lead_steps, loihi_spikes, pad
from snncc.targets.loihi.options import LoihiOptions

CNN = Path(__file__).resolve().parents[1] / "data" / "nir" / "cnn_sinabs.nir"


def _frames(batch, steps, width, p, seed):
    return (np.random.default_rng(seed).random((batch, steps, width)) < p).astype(np.uint8)


def _sinabs_by_hand(path: Path, x: np.ndarray) -> list[np.ndarray]:
    """The Sinabs CNN written directly in torch from the NIR nodes (independent of snncc's frontend):
    conv / sum pool / linear, then IF: v += input; spike where v > threshold; v <- 0 there."""
    g = nir.read(str(path))
    n = g.nodes
    t = lambda a: torch.tensor(np.asarray(a, np.float64))                        # noqa: E731
    conv = lambda k, h: F.conv2d(h, t(n[k].weight), t(n[k].bias), stride=tuple(n[k].stride),   # noqa: E731
                                 padding=tuple(n[k].padding), dilation=tuple(n[k].dilation), groups=n[k].groups)
    pool = lambda k, h: F.avg_pool2d(h, tuple(n[k].kernel_size), tuple(n[k].stride)) * 4.0   # noqa: E731
    lin = lambda k, h: h.flatten(1) @ t(n[k].weight).T + t(n[k].bias)                       # noqa: E731
    stages = [lambda h: conv("0", h), lambda h: conv("2", h), lambda h: conv("5", pool("4", h)),
              lambda h: lin("9", pool("7", h)), lambda h: lin("11", h)]
    batch, steps, _ = x.shape
    v = [None] * len(stages)
    out = [[] for _ in stages]
    for step in range(steps):
        h = torch.tensor(x[:, step].reshape(batch, 2, 34, 34), dtype=torch.float64)
        for i, stage in enumerate(stages):
            drive = stage(h)
            v[i] = drive if v[i] is None else v[i] + drive
            s = (v[i] > 1.0).to(torch.float64)
            v[i] = torch.where(s > 0, torch.zeros_like(v[i]), v[i])
            out[i].append(s.reshape(batch, -1).numpy())
            h = s
    return [np.stack(o, axis=1) for o in out]


def test_cnn_sinabs_ir_equals_the_network_written_by_hand():
    graph = load_model(CNN, LoadOptions())
    assert graph.dt == 1.0 and any("dt = 1" in note for note in graph.metadata["import_notes"])
    convs = [graph.node(n) for n in graph.of_kind(Conv)]
    assert [c.in_shape for c in convs] == [(2, 34, 34), (16, 16, 16), (16, 16, 16), (16, 8, 8), (8, 8, 8)]
    x = _frames(2, 12, 2312, 0.08, seed=3)
    sim = simulate(graph, x, record="spikes")
    hand = _sinabs_by_hand(CNN, x)
    lifs = graph.of_kind(LIF)
    assert [graph.node(n).n for n in lifs] == [4096, 4096, 512, 256, 10]
    for name, want in zip(lifs, hand):
        np.testing.assert_array_equal(np.asarray(sim.spikes[name]), want)
    assert hand[2].sum() > 0 and hand[-1].sum() > 0


def _small_cnn(rng) -> nir.NIRGraph:
    """2x10x10 -> conv 4ch (3x3, stride 1, pad 1) -> IF -> sum pool 2 -> conv 4ch (groups 2, dilation 2,
    pad 2) -> IF -> avg pool (3x3, stride 2, pad 1) -> flatten -> affine 5 -> IF."""
    def if_(shape, thr=1.0):
        return nir.IF(r=np.ones(shape), v_threshold=np.full(shape, thr))

    nodes = {
        "input": nir.Input(np.array([2, 10, 10])),
        "c1": nir.Conv2d(input_shape=(10, 10), weight=rng.normal(0.4, 0.5, (4, 2, 3, 3)), stride=1, padding=1,
                         dilation=1, groups=1, bias=rng.normal(0, 0.05, 4)),
        "n1": if_((4, 10, 10)),
        "p1": nir.SumPool2d(kernel_size=np.array([2, 2]), stride=np.array([2, 2]), padding=np.array([0, 0])),
        "c2": nir.Conv2d(input_shape=(5, 5), weight=rng.normal(0.3, 0.4, (4, 2, 3, 3)), stride=1, padding=2,
                         dilation=2, groups=2, bias=np.zeros(4)),
        "n2": if_((4, 5, 5)),
        "p2": nir.AvgPool2d(kernel_size=np.array([3, 3]), stride=np.array([2, 2]), padding=np.array([1, 1])),
        "f": nir.Flatten(input_type={"input": np.array([4, 3, 3])}),
        "fc": nir.Affine(weight=rng.normal(0.2, 0.6, (5, 36)), bias=np.zeros(5)),
        "n3": if_((5,), 0.5),
        "output": nir.Output(np.array([5])),
    }
    chain = ["input", "c1", "n1", "p1", "c2", "n2", "p2", "f", "fc", "n3", "output"]
    return nir.NIRGraph(nodes=nodes, edges=list(zip(chain[:-1], chain[1:])), type_check=False)


@pytest.fixture(scope="module")
def small_cnn(tmp_path_factory):
    path = tmp_path_factory.mktemp("cnn") / "small.nir"
    nir.write(str(path), _small_cnn(np.random.default_rng(7)))
    return path


def test_small_cnn_jetson_artefact_equals_the_ir(small_cnn, tmp_path, capsys):
    out = tmp_path / "jet"
    code, _, err = run_cli(["compile", small_cnn, "--target", "jetson", "-o", out, "--time-steps", 16], capsys)
    assert code == 0, err
    graph = load_model(small_cnn, LoadOptions())
    x = _frames(8, 16, 200, 0.15, seed=4)
    expected = np.asarray(simulate(graph, x).output)
    session = ort.InferenceSession(str(out / "model.onnx"), providers=["CPUExecutionProvider"])
    assert "Conv" in {node.op_type for node in __import__("onnx").load(str(out / "model.onnx")).graph.node}
    _, spikes = session.run(["counts", "output_spikes"], {"events": x.astype(np.float32)})
    assert expected.sum() > 0
    np.testing.assert_array_equal(spikes, expected.astype(np.float32))


def test_small_cnn_loihi_bundle_emulates_the_quantized_ir_exactly(small_cnn, tmp_path, capsys):
    out = tmp_path / "cnn.net"
    code, stdout, err = run_cli(["compile", small_cnn, "--target", "loihi", "-o", out, "--time-steps", "40"], capsys)
    assert code == 0, err
    assert "expanded to connection matrices" in stdout
    graph = load_model(small_cnn, LoadOptions())
    lowered = lower_model(graph, LoihiOptions(), t_sample=40)
    net = read_bundle(out)
    x = _frames(6, 40, 200, 0.15, seed=5)
    rec = lowered.timing_record
    res = emulate(net, pad(x, lead_steps(rec.shifts, rec.output_shift)), record="all")
    emu = loihi_spikes(res, net, lowered.layers, rec.shifts, 40)
    quant = simulate(lowered.quantized, x, record="spikes")
    flt = simulate(graph, x, record="spikes")
    for name in emu:
        np.testing.assert_array_equal(emu[name], np.asarray(quant.spikes[name]))
        assert np.mean(emu[name] == np.asarray(flt.spikes[name])) > 0.9
    assert emu[lowered.layers[-1].lif].sum() > 0


def test_cnn_sinabs_compiles_for_both_targets(tmp_path, capsys, cnn_loihi_bundle):
    code, _, err = run_cli(["compile", CNN, "--target", "jetson", "-o", tmp_path / "jet", "--time-steps", 4], capsys)
    assert code == 0, err
    assert (tmp_path / "jet" / "model.onnx").exists()
    bundle, _ = cnn_loihi_bundle(capsys)   # snncc compile CNN --target loihi --time-steps 12 (exit 0), once a session
    net = read_bundle(bundle)
    assert [lay.n for lay in net.layers] == [2312, 4096, 4096, 512, 256, 10]
    assert int(np.count_nonzero(net.layers[2].weight)) < 0.05 * net.layers[2].weight.size   # conv: sparse synapses
    # the bundle emulated on a reduced N-MNIST-shaped input, against the float graph (bounds below the
    # agreement measured by bench/studies/cnn_sinabs_agreement.py: 8-bit weights, no leak, see docs/conv.md)
    graph = load_model(CNN, LoadOptions())
    x = _frames(2, 12, 2312, 0.05, seed=8)
    shifts = net.metadata["population_shifts"]
    res = emulate(net, pad(x, net.t_sample - 12), record="all")
    ref = simulate(graph, x, record="spikes")
    for i, name in enumerate(graph.of_kind(LIF), start=1):
        got = res.spikes[i][:, shifts.get(name, 0):shifts.get(name, 0) + 12]
        assert np.mean(got == np.asarray(ref.spikes[name])) > 0.85, name
    assert ref.spikes["1"].sum() > 0
