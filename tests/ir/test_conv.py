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
    sim = simulate(_graph(op), x.reshape(2, 3, -1)).output.numpy().reshape(6, -1)
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
    np.testing.assert_allclose(simulate(_graph(op), x[None]).output.numpy()[0], want, rtol=0, atol=1e-12)
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
