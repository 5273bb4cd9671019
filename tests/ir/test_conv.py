"""The IR's Conv node: the simulator and the explicit connection matrix against PyTorch's own
conv1d / conv2d / avg_pool2d, over stride, padding, groups and dilation."""

import numpy as np
import pytest
import torch
from torch.nn import functional as F

from snncc.errors import SnnccError
from snncc.frontends.nir_conv import pool_node
from snncc.ir import Conv, Graph, Input, Output, load_graph, save_graph, simulate, validate
from snncc.ir.conv import conv_bias_vector, conv_matrix

CASES = [  # (in_shape, out_channels, kernel, stride, padding, dilation, groups)
    ((2, 9, 8), 4, (3, 3), (1, 1), (0, 0), (1, 1), 1),
    ((4, 11, 10), 6, (3, 2), (2, 1), (1, 2), (1, 2), 2),
    ((2, 34, 34), 3, (5, 5), (2, 2), (1, 1), (1, 1), 1),
    ((6, 7, 9), 6, (3, 3), (1, 2), (2, 1), (2, 1), 6),
    ((4, 13), 4, (3,), (2,), (1,), (2,), 2),
]


def _graph(op: Conv) -> Graph:
    g = Graph(dt=1.0)
    g.add("x", Input(width=op.in_size, signal="analog"))
    g.add("conv", op)
    g.add("y", Output(width=op.size))
    g.connect("x", "conv")
    g.connect("conv", "y")
    return validate(g)


def _torch_conv(op: Conv, x: np.ndarray) -> np.ndarray:
    fn = F.conv1d if op.spatial_dims == 1 else F.conv2d
    y = fn(torch.tensor(x.reshape((-1,) + op.in_shape)), torch.tensor(op.weight),
           None if op.bias is None else torch.tensor(op.bias), stride=op.stride, padding=op.padding,
           dilation=op.dilation, groups=op.groups)
    return y.reshape(x.shape[0], -1).numpy()


@pytest.mark.parametrize("in_shape,out_ch,kernel,stride,padding,dilation,groups", CASES)
def test_conv_matches_torch_in_the_simulator_and_as_a_matrix(in_shape, out_ch, kernel, stride, padding, dilation,
                                                             groups):
    rng = np.random.default_rng(sum(in_shape))
    op = Conv(weight=rng.normal(size=(out_ch, in_shape[0] // groups) + kernel), in_shape=in_shape, stride=stride,
              padding=padding, dilation=dilation, groups=groups, bias=rng.normal(size=out_ch))
    x = rng.normal(size=(6, int(np.prod(in_shape))))
    want = _torch_conv(op, x)
    assert op.size == want.shape[1]
    sim = np.asarray(simulate(_graph(op), x.reshape(2, 3, -1)).output).reshape(6, -1)
    np.testing.assert_allclose(sim, want, rtol=0, atol=1e-12)
    a = conv_matrix(op)
    assert a.shape == (op.size, op.in_size)
    np.testing.assert_allclose(a @ x.T + conv_bias_vector(op)[:, None], want.T, rtol=0, atol=1e-12)


@pytest.mark.parametrize("kind", ["SumPool2d", "AvgPool2d"])
@pytest.mark.parametrize("kernel,stride,padding", [((2, 2), (2, 2), (0, 0)), ((3, 2), (2, 1), (1, 1))])
def test_pooling_is_a_fixed_depthwise_conv(kind, kernel, stride, padding):
    class Node:  # a NIR pooling node's fields
        kernel_size, input_type = np.array(kernel), {"input": np.array([3, 8, 7])}

    Node.stride, Node.padding = np.array(stride), np.array(padding)
    op = pool_node("pool", kind, Node())
    x = np.random.default_rng(1).normal(size=(4, op.in_size))
    avg = F.avg_pool2d(torch.tensor(x.reshape(4, 3, 8, 7)), kernel, stride, padding, count_include_pad=True)
    want = avg.reshape(4, -1).numpy() * (np.prod(kernel) if kind == "SumPool2d" else 1)
    np.testing.assert_allclose(np.asarray(simulate(_graph(op), x[None]).output)[0], want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(conv_matrix(op) @ x.T, want.T, rtol=0, atol=1e-12)


def test_bad_conv_fields_are_one_line_errors(tmp_path):
    w = np.ones((4, 2, 3, 3))
    with pytest.raises(SnnccError, match="groups must be >= 1 and divide"):
        _graph(Conv(weight=w, in_shape=(6, 8, 8), groups=3))
    with pytest.raises(SnnccError, match="input channels"):
        _graph(Conv(weight=w, in_shape=(3, 8, 8)))
    with pytest.raises(SnnccError, match="does not fit the padded input"):
        _graph(Conv(weight=w, in_shape=(2, 2, 8)))
    with pytest.raises(SnnccError, match="stride"):
        _graph(Conv(weight=w, in_shape=(2, 8, 8), stride=(0, 1)))


def test_conv_graph_round_trips_through_the_ir_file(tmp_path):
    op = Conv(weight=np.arange(24.0).reshape(4, 1, 3, 2), in_shape=(2, 5, 6), stride=(2, 1), padding=(1, 0),
              dilation=(1, 2), groups=2, bias=np.ones(4))
    save_graph(_graph(op), tmp_path / "c.snnir")
    back = load_graph(tmp_path / "c.snnir").node("conv")
    assert (back.in_shape, back.stride, back.padding, back.dilation, back.groups) == (
        op.in_shape, op.stride, op.padding, op.dilation, op.groups)
    assert np.array_equal(back.weight, op.weight) and np.array_equal(back.bias, op.bias)


def test_folding_linear_chains_keeps_the_graph_meaning():
    from snncc.ir import LIF, Dense, Readout
    from snncc.passes.fold_linear import fold_linear

    rng = np.random.default_rng(2)
    g = Graph(dt=1e-3)
    g.add("x", Input(width=2 * 6 * 6))
    g.add("c1", Conv(weight=rng.normal(0.3, 0.5, (4, 2, 3, 3)), in_shape=(2, 6, 6), padding=(1, 1),
                     bias=rng.normal(0, 0.1, 4)))
    g.add("pool", Conv(weight=np.ones((4, 1, 2, 2)), in_shape=(4, 6, 6), stride=(2, 2), groups=4))
    g.add("fc", Dense(weight=rng.normal(0.2, 0.4, (5, 36)), bias=np.zeros(5)))
    g.add("n", LIF(n=5, tau_syn=5e-3, tau_mem=2e-2, threshold=1.0))
    g.add("readout", Readout(width=5))
    g.add("y", Output(width=5))
    for a, b, d in [("x", "c1", 2), ("c1", "pool", 0), ("pool", "fc", 0), ("fc", "n", 1), ("n", "readout", 0),
                    ("readout", "y", 0)]:
        g.connect(a, b, delay=d)
    folded, rec = fold_linear(validate(g))
    assert rec.convs == ["c1", "pool"] and rec.merged == ["c1+pool", "pool+fc"] and rec.zero_biases == ["fc"]
    assert [n for n in folded] == ["x", "fc", "n", "readout", "y"] and folded.delay("x", "fc") == 2
    x = (rng.random((3, 30, 72)) < 0.3).astype(np.float64)
    a, b = simulate(g, x, record="all"), simulate(validate(folded), x, record="all")
    np.testing.assert_allclose(np.asarray(a.voltage["n"]), np.asarray(b.voltage["n"]), atol=1e-9)
    assert a.spikes["n"].sum() > 0 and np.array_equal(np.asarray(a.spikes["n"]), np.asarray(b.spikes["n"]))
    assert fold_linear(folded)[0] is folded          # nothing left to fold: the graph itself


def test_nir_conv1d_and_string_padding_load_with_their_meaning():
    import nir

    from snncc.frontends.nir import graph_from_nir

    rng = np.random.default_rng(4)
    w = rng.normal(size=(3, 2, 3))
    nodes = {"input": nir.Input(np.array([2, 9])),
             "c": nir.Conv1d(input_shape=9, weight=w, stride=1, padding="same", dilation=2, groups=1,
                             bias=rng.normal(size=3)),
             "output": nir.Output(np.array([3, 9]))}
    g = graph_from_nir(nir.NIRGraph(nodes=nodes, edges=[("input", "c"), ("c", "output")], type_check=False), dt=1.0)
    op = g.node("c")
    assert op.in_shape == (2, 9) and op.padding == (2,) and op.out_shape == (3, 9)
    x = rng.normal(size=(4, 18))
    want = F.conv1d(torch.tensor(x.reshape(4, 2, 9)), torch.tensor(w), torch.tensor(nodes["c"].bias), padding=2,
                    dilation=2).reshape(4, -1).numpy()
    np.testing.assert_allclose(np.asarray(simulate(g, x[None]).output)[0], want, atol=1e-12)


def test_nir_neuron_gain_folds_into_the_conv_kernel_per_channel():
    import nir

    from snncc.frontends.nir import graph_from_nir

    w = np.random.default_rng(5).normal(size=(2, 1, 3, 3))
    r = np.ones((2, 4, 4)) * np.array([0.5, 2.0])[:, None, None]       # one resistance per output channel
    nodes = {"input": nir.Input(np.array([1, 6, 6])),
             "c": nir.Conv2d(input_shape=(6, 6), weight=w, stride=1, padding=0, dilation=1, groups=1, bias=np.zeros(2)),
             "n": nir.IF(r=r, v_threshold=np.ones((2, 4, 4))), "output": nir.Output(np.array([2, 4, 4]))}
    g = graph_from_nir(nir.NIRGraph(nodes=nodes, edges=[("input", "c"), ("c", "n"), ("n", "output")],
                                    type_check=False), dt=1.0)
    assert g.of_kind(Conv) == ["c"] and len(list(g)) == 5                # no extra gain node
    np.testing.assert_array_equal(g.node("c").weight, w * np.array([0.5, 2.0])[:, None, None, None])
