"""Convolutional NIR nodes -> IR ``Conv`` nodes (called by ``frontends/nir.py``).

Conv1d / Conv2d:  y = conv(x) + b, PyTorch's convNd (cross-correlation). NIR stores only the
                  spatial input shape; the channels are weight.shape[1] * groups. Padding 'valid'
                  is 0; 'same' is (dilation*(kernel-1))/2 per side, refused when that is odd
                  (PyTorch pads such a case unevenly, which the IR's symmetric padding cannot state).
SumPool2d:        y[c, p] = sum over the window of x[c, .] = a Conv with a ones kernel, one group
                  per channel (zero padding adds nothing).
AvgPool2d:        the window mean with zero padding counted (PyTorch's default count_include_pad):
                  a Conv with kernel 1/(kh*kw), one group per channel.
Flatten:          the identity (the IR's vectors are the C-order flattening of NIR's shapes).
IF/LIF/CubaLIF on (C, H, W) shapes are populations of C*H*W neurons in C order.
The channels of a pooling node come from its ``input_type`` (NIR writes it for a typed graph).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.nodes import Conv
from snncc.limits import check_real

CONV_KINDS = ("Conv1d", "Conv2d")
POOL_KINDS = ("SumPool2d", "AvgPool2d")
KINDS = CONV_KINDS + POOL_KINDS
NON_LEAKY = ("IF", "I", "Threshold")        # neuron kinds whose equations have no time constant
LEAKY = ("LIF", "CubaLIF", "LI", "CubaLI")


MINIMUM = {"stride": 1, "dilation": 1, "kernel_size": 1, "input_shape": 1, "padding": 0, "groups": 1}


def _ints(value: Any, dims: int, name: str, field: str) -> tuple[int, ...]:
    """``value`` as ``dims`` integers, each at least ``MINIMUM[field]`` (a stride of 0 would divide by zero)."""
    arr = np.asarray(value).reshape(-1)
    if arr.size == 1:
        arr = np.repeat(arr, dims)
    if arr.size != dims or arr.dtype.kind not in "biuf" or not np.all(np.isfinite(arr.astype(np.float64))) \
            or not np.all(np.equal(np.mod(arr.astype(np.float64), 1), 0)):
        raise SnnccError(f"must be {dims} integer(s), got {np.asarray(value).tolist()}", field=f"node '{name}'.{field}")
    low = MINIMUM.get(field, 0)
    if np.any(arr < low):
        raise SnnccError(f"must be >= {low}, got {np.asarray(value).tolist()}", field=f"node '{name}'.{field}")
    return tuple(int(a) for a in arr)


def check_raw_fields(f: Any, where: str = "") -> None:
    """Check the integer fields of every convolution and pooling node in an open NIR HDF5 file
    (``node/nodes/...``) before ``nir.read`` builds the nodes (it divides by the stride)."""
    import h5py

    nodes = f.get("node/nodes") if not where else f
    if not isinstance(nodes, h5py.Group):
        return
    for name in nodes:
        group = nodes.get(name)
        if not isinstance(group, h5py.Group):
            continue
        kind = group.get("type")
        kind = kind[()] if isinstance(kind, h5py.Dataset) and kind.size == 1 else b""
        kind = kind.decode("utf-8", "replace") if isinstance(kind, bytes) else str(kind)
        path = f"{where}{name}"
        if kind == "NIRGraph" and isinstance(group.get("nodes"), h5py.Group):
            check_raw_fields(group["nodes"], path + ".")
        elif kind in KINDS:
            dims = 1 if kind == "Conv1d" else 2
            for field in ("stride", "dilation", "kernel_size", "padding"):
                ds = group.get(field)
                if isinstance(ds, h5py.Dataset) and ds.size <= 16 and ds.dtype.kind in "biuf":
                    _ints(ds[()], dims, path, field)


def _padding(name: str, node: Any, kernel: tuple[int, ...], dilation: tuple[int, ...]) -> tuple[int, ...]:
    pad = node.padding
    if isinstance(pad, str):
        if pad == "valid":
            return (0,) * len(kernel)
        if pad == "same":
            if any(s != 1 for s in _ints(node.stride, len(kernel), name, "stride")):
                raise SnnccError("padding 'same' needs stride 1", field=f"node '{name}'.padding")
            total = [d * (k - 1) for k, d in zip(kernel, dilation)]
            if any(t % 2 for t in total):
                raise SnnccError("padding 'same' with an even (dilated) kernel pads unevenly; the IR pads both "
                                 "sides alike", field=f"node '{name}'.padding")
            return tuple(t // 2 for t in total)
        raise SnnccError(f"padding must be an integer, 'same' or 'valid', got {pad!r}", field=f"node '{name}'.padding")
    return _ints(pad, len(kernel), name, "padding")


def _spatial(name: str, node: Any, dims: int) -> tuple[int, ...]:
    shape = getattr(node, "input_shape", None)
    if shape is None:
        raise SnnccError("the convolution has no input_shape (NIR needs it to fix the output shape)",
                         field=f"node '{name}'.input_shape")
    return _ints(shape, dims, name, "input_shape")


def conv_node(name: str, kind: str, node: Any) -> Conv:
    """An IR Conv for a NIR Conv1d/Conv2d."""
    check_real(node.weight, field=f"node '{name}'.weight")
    if getattr(node, "bias", None) is not None:
        check_real(node.bias, field=f"node '{name}'.bias")
    w = np.asarray(node.weight, dtype=np.float64)
    dims = 1 if kind == "Conv1d" else 2
    if w.ndim != dims + 2:
        raise SnnccError(f"weight must have {dims + 2} dims (out, in/groups, kernel...), got shape {w.shape}",
                         field=f"node '{name}'.weight")
    groups = int(np.asarray(node.groups).reshape(-1)[0]) if getattr(node, "groups", None) is not None else 1
    kernel = tuple(int(k) for k in w.shape[2:])
    dilation = _ints(node.dilation if getattr(node, "dilation", None) is not None else 1, dims, name, "dilation")
    stride = _ints(node.stride if getattr(node, "stride", None) is not None else 1, dims, name, "stride")
    bias = getattr(node, "bias", None)
    if bias is not None:
        bias = np.broadcast_to(np.asarray(bias, dtype=np.float64).reshape(-1), (w.shape[0],)).copy()
        if not np.any(bias):
            bias = None
    return Conv(weight=w, in_shape=(w.shape[1] * groups,) + _spatial(name, node, dims), stride=stride,
                padding=_padding(name, node, kernel, dilation), dilation=dilation, groups=groups, bias=bias)


def _typed(node: Any, key: str) -> np.ndarray | None:
    value = (getattr(node, f"{key}_type", None) or {}).get(key)
    if value is None or np.asarray(value).size == 0 or np.any(np.asarray(value) <= 0):
        return None
    return np.asarray(value).reshape(-1).astype(np.int64)


def output_shape(name: str, nodes: dict[str, Any], kinds: dict[str, str], preds: dict[str, list[str]],
                 depth: int = 0) -> tuple[int, ...] | None:
    """The shape of node ``name``'s output as the graph states it: its output_type, its parameter
    arrays (a neuron's r or threshold of shape (C, H, W)), a convolution's computed output, or, for
    shape-keeping nodes (neurons without shaped parameters, Delay, Scale), its input's shape."""
    node, kind = nodes.get(name), kinds.get(name)
    if node is None or depth > 64:
        return None
    typed = _typed(node, "output")
    if typed is not None:
        return tuple(int(v) for v in typed)
    if kind in KINDS:
        return convert(name, kind, node, nodes, kinds, preds, depth + 1).out_shape
    for attr in ("r", "v_threshold", "threshold", "tau", "tau_mem", "delay", "scale"):
        arr = getattr(node, attr, None)
        if arr is not None and np.ndim(arr) >= 2:
            return tuple(int(v) for v in np.shape(arr))
    if kind in ("Flatten", "Affine", "Linear", "Input", "Output"):
        return None
    up = preds.get(name, [])
    return output_shape(up[0], nodes, kinds, preds, depth + 1) if len(up) == 1 else None


def pool_node(name: str, kind: str, node: Any, in_type=None) -> Conv:
    """An IR Conv (fixed depthwise kernel) for a NIR SumPool2d/AvgPool2d."""
    if in_type is None:
        in_type = _typed(node, "input")
    if in_type is None or np.asarray(in_type).size != 3:
        raise SnnccError("pooling needs its (channels, height, width) input shape; neither the node's input_type "
                         "nor the node feeding it states one", field=f"node '{name}'.input_type")
    channels, height, width = (int(v) for v in np.asarray(in_type).reshape(-1))
    kernel = _ints(node.kernel_size, 2, name, "kernel_size")
    stride = _ints(node.stride if getattr(node, "stride", None) is not None else kernel, 2, name, "stride")
    padding = _ints(node.padding if getattr(node, "padding", None) is not None else 0, 2, name, "padding")
    value = 1.0 if kind == "SumPool2d" else 1.0 / (kernel[0] * kernel[1])
    weight = np.full((channels, 1) + kernel, value)
    return Conv(weight=weight, in_shape=(channels, height, width), stride=stride, padding=padding, groups=channels)


def convert(name: str, kind: str, node: Any, nodes: dict[str, Any] | None = None, kinds: dict[str, str] | None = None,
            preds: dict[str, list[str]] | None = None, depth: int = 0) -> Conv:
    """The IR node for one convolutional NIR node (``kind`` in KINDS); ``nodes``/``kinds``/``preds``
    (the flattened graph) let a pooling node without an input_type take its input's shape."""
    if kind in CONV_KINDS:
        op = conv_node(name, kind, node)
    else:
        in_type = _typed(node, "input")
        up = (preds or {}).get(name, [])
        if in_type is None and len(up) == 1 and nodes is not None:
            in_type = output_shape(up[0], nodes, kinds or {}, preds or {}, depth + 1)
        op = pool_node(name, kind, node, in_type)
    if min(op.out_shape[1:]) < 1:
        raise SnnccError(f"the kernel does not fit the padded input (output shape {op.out_shape})",
                         field=f"node '{name}'")
    out_type = (getattr(node, "output_type", None) or {}).get("output")
    if out_type is not None and np.asarray(out_type).size and int(np.prod(np.asarray(out_type))) != op.size \
            and np.all(np.asarray(out_type) > 0):
        raise SnnccError(f"output_type {np.asarray(out_type).tolist()} disagrees with the shape the parameters give "
                         f"{list(op.out_shape)}", field=f"node '{name}'.output_type")
    return op


def scaled_rows(op: Conv, gain: np.ndarray) -> Conv | None:
    """``op`` with output neuron j's row scaled by gain[j], when the gain is one value per output
    channel (then it scales the kernel and bias of that channel); else None."""
    per_pos = int(np.prod(op.out_shape[1:]))
    g = np.asarray(gain, np.float64).reshape(op.out_shape[0], per_pos)
    if not np.all(g == g[:, :1]):
        return None
    c = g[:, 0]
    return Conv(weight=op.weight * c.reshape((-1,) + (1,) * (op.weight.ndim - 1)), in_shape=op.in_shape,
                stride=op.stride, padding=op.padding, dilation=op.dilation, groups=op.groups,
                bias=None if op.bias is None else op.bias * c)


def non_leaky_only(kinds: dict[str, str]) -> bool:
    """True when the graph's neurons all lack time constants (IF, I, Threshold) -- there is then no
    time scale in the graph to infer dt from."""
    neurons = [k for k in kinds.values() if k in NON_LEAKY + LEAKY]
    return bool(neurons) and all(k in NON_LEAKY for k in neurons)


NON_LEAKY_DT_NOTE = ("dt = 1: the graph's neurons have no time constant (IF/I), so NIR's time unit is taken as one "
                     "step (discrete-time exports such as Sinabs' IF with r = 1 mean v += input per step); pass --dt "
                     "to integrate dv/dt = r*I at another step")
