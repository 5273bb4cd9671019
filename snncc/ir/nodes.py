"""IR node types: small records, each stating its equation (the meaning lives in ``simulate``).

Per-neuron parameters are stored as float64 arrays of shape ``(n,)`` (a scalar given by a
frontend is broadcast), weights as float64 arrays. Time constants are in seconds; the graph
holds the global ``dt``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

RESETS = ("zero", "subtract")
DISCRETISATIONS = ("exp", "euler")
BIAS_PLACEMENTS = ("current", "voltage")
READOUT_MODES = ("spike_count", "membrane_max", "last")
FIRE_TESTS = (">", ">=")   # LIF threshold test: V > theta (default) or V >= theta (Xylo's integer test)
INPUT_KINDS = ("spikes", "analog")


def _vector(value: Any, n: int) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim == 0:
        return np.full(n, float(arr))
    return arr.reshape(-1).copy()


def _matrix(value: Any) -> np.ndarray:
    return np.array(value, dtype=np.float64, copy=True)


@dataclass(eq=False)
class Node:
    """Base of every node: ``size`` is the width of the node's output at each time step."""

    kind: ClassVar[str] = "node"

    @property
    def size(self) -> int:  # pragma: no cover - every subclass overrides
        raise NotImplementedError

    def arrays(self) -> dict[str, np.ndarray]:
        """The node's array-valued fields (for serialisation and hashing)."""
        return {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if isinstance(getattr(self, f.name), np.ndarray)
        }

    def scalars(self) -> dict[str, Any]:
        """The node's non-array fields."""
        return {
            f.name: getattr(self, f.name)
            for f in dataclasses.fields(self)
            if not isinstance(getattr(self, f.name), np.ndarray)
        }


@dataclass(eq=False)
class Input(Node):
    """External stream x[t] of ``width`` channels: ``spikes`` (0/1) or ``analog`` values."""

    kind: ClassVar[str] = "Input"
    width: int
    signal: str = "spikes"

    @property
    def size(self) -> int:
        return int(self.width)


@dataclass(eq=False)
class Dense(Node):
    """y[t] = W @ x[t] (+ b).  W has shape (out, in). A bias enters whatever the output feeds
    (for a LIF: the current, every step from t = 0)."""

    kind: ClassVar[str] = "Dense"
    weight: np.ndarray
    bias: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.weight = _matrix(self.weight)
        if self.bias is not None:
            self.bias = _vector(self.bias, self.weight.shape[0] if self.weight.ndim == 2 else 1)

    @property
    def size(self) -> int:
        return int(self.weight.shape[0])

    @property
    def in_size(self) -> int:
        return int(self.weight.shape[1])


def _ints(value: Any, dims: int, name: str) -> tuple[int, ...]:
    """A per-dimension integer parameter: one int for every spatial dimension, or one each."""
    arr = np.asarray(value).reshape(-1)
    if arr.size == 1 and dims != 1:
        arr = np.repeat(arr, dims)
    if arr.size != dims or not np.all(np.equal(np.mod(arr, 1), 0)):
        raise ValueError(f"{name} must be {dims} integer(s), got {value!r}")
    return tuple(int(a) for a in arr)


@dataclass(eq=False)
class Conv(Node):
    """Convolution over a C-order flattened (C, *spatial) map, 1 to 3 spatial dims (PyTorch's convNd:
    cross-correlation, zero padding, no kernel flip).

    y[o, p] = b[o] + sum_{c < C/groups} sum_k W[o, c, k] * x[g(o)*C/groups + c, p*stride - padding + k*dilation]
    with g(o) = o // (O/groups), x = 0 outside the input, per spatial dim
    out = floor((in + 2*padding - dilation*(kernel - 1) - 1) / stride) + 1.
    ``in_shape`` = (C, *spatial). Pooling is this node with a fixed kernel (sum: ones, one group per
    channel; average: 1/kernel size, zero padding counted, as PyTorch's count_include_pad).
    """

    kind: ClassVar[str] = "Conv"
    weight: np.ndarray                      # (O, C/groups, *kernel)
    in_shape: tuple = ()
    stride: tuple = ()
    padding: tuple = ()
    dilation: tuple = ()
    groups: int = 1
    bias: np.ndarray | None = None          # (O,)

    def __post_init__(self) -> None:
        self.weight = _matrix(self.weight)
        self.in_shape = tuple(int(v) for v in np.asarray(self.in_shape).reshape(-1))
        dims = max(self.weight.ndim - 2, 0)
        self.stride = _ints(self.stride if np.size(self.stride) else 1, dims, "stride")
        self.padding = _ints(self.padding if np.size(self.padding) else 0, dims, "padding")
        self.dilation = _ints(self.dilation if np.size(self.dilation) else 1, dims, "dilation")
        self.groups = int(self.groups)
        if self.bias is not None:
            self.bias = _vector(self.bias, self.weight.shape[0] if self.weight.ndim else 1)

    @property
    def spatial_dims(self) -> int:
        return self.weight.ndim - 2

    @property
    def kernel(self) -> tuple[int, ...]:
        return tuple(int(k) for k in self.weight.shape[2:])

    @property
    def out_shape(self) -> tuple[int, ...]:
        spatial = tuple(
            (n + 2 * p - d * (k - 1) - 1) // max(s, 1) + 1   # (stride 0 is refused by validation)
            for n, p, d, k, s in zip(self.in_shape[1:], self.padding, self.dilation, self.kernel, self.stride))
        return (int(self.weight.shape[0]),) + spatial

    @property
    def size(self) -> int:
        return int(np.prod(self.out_shape))

    @property
    def in_size(self) -> int:
        return int(np.prod(self.in_shape))


@dataclass(eq=False)
class LIF(Node):
    """Current-based leaky integrate-and-fire population, integrate then fire.

    alpha = exp(-dt/tau_syn), beta = exp(-dt/tau_mem)   (discretisation "exp")
    alpha = 1 - dt/tau_syn,   beta = 1 - dt/tau_mem     (discretisation "euler")
    I[t] = alpha*I[t-1] + sum_k in_k[t]  (+ bias if bias_placement == "current")
    V[t] = beta*V[t-1] + I[t]            (+ bias if bias_placement == "voltage")
    V[t] = 0 while refractory;  s[t] = V[t] > threshold (strict)
    on a spike: V = 0 (reset "zero") or V -= threshold ("subtract"); then V is held at 0 for
    refractory - 1 further steps.
    A threshold of +inf gives a non-spiking leaky integrator (NIR's LI).

    Spike rule (defaults give the above exactly): ``fire_test`` is ">" or ">=" (V >= threshold,
    as an integer chip compares); ``max_spikes`` m >= 1 lets one step emit several spikes:
    s[t] = the number of times the test holds while threshold is subtracted, at most m,
        ">=": s = min(m, floor(V / theta))   for V >= theta, else 0
        ">" : s = min(m, ceil(V / theta) - 1) for V > theta, else 0
    then V -= s*theta ("subtract") or V = 0 where s > 0 ("zero"). The spikes port carries the
    count s, so a Dense after it delivers s * W (Xylo's hidden neurons fire up to 31 per step).
    """

    kind: ClassVar[str] = "LIF"
    n: int
    tau_syn: np.ndarray
    tau_mem: np.ndarray
    threshold: np.ndarray
    reset: str = "zero"
    refractory: int = 1
    discretisation: str = "exp"
    bias: np.ndarray | None = None
    bias_placement: str = "current"
    max_spikes: int = 1
    fire_test: str = ">"

    # fields a serialised graph leaves out while they hold these values (files stay as before)
    OMIT_AT_DEFAULT: ClassVar[dict[str, Any]] = {"max_spikes": 1, "fire_test": ">"}

    def __post_init__(self) -> None:
        self.n = int(self.n)
        self.max_spikes = int(self.max_spikes)
        self.tau_syn = _vector(self.tau_syn, self.n)
        self.tau_mem = _vector(self.tau_mem, self.n)
        self.threshold = _vector(self.threshold, self.n)
        if self.bias is not None:
            self.bias = _vector(self.bias, self.n)
        self.refractory = int(self.refractory)

    @property
    def size(self) -> int:
        return self.n

    @property
    def standard_spikes(self) -> bool:
        """One spike per step at most, on V > threshold: the rule every model is trained with."""
        return self.max_spikes == 1 and self.fire_test == ">"

    def decays(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(alpha, beta) per neuron for this population's discretisation."""
        if self.discretisation == "euler":
            return 1.0 - dt / self.tau_syn, 1.0 - dt / self.tau_mem
        return np.exp(-dt / self.tau_syn), np.exp(-dt / self.tau_mem)


@dataclass(eq=False)
class LSTM(Node):
    """Standard LSTM cell, PyTorch gate order (i, f, g, o):

    gates = W_ih @ x[t] + W_hh @ h[t-1] + b_ih (+ b_hh)
    i, f, o = sigmoid(.), g = tanh(.);  c[t] = f*c[t-1] + i*g;  h[t] = o*tanh(c[t])
    One bias vector (the paper's parameter count) when ``bias_hh`` is None.
    """

    kind: ClassVar[str] = "LSTM"
    weight_ih: np.ndarray
    weight_hh: np.ndarray
    bias_ih: np.ndarray | None = None
    bias_hh: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.weight_ih = _matrix(self.weight_ih)
        self.weight_hh = _matrix(self.weight_hh)
        rows = self.weight_ih.shape[0] if self.weight_ih.ndim == 2 else 0
        if self.bias_ih is not None:
            self.bias_ih = _vector(self.bias_ih, rows)
        if self.bias_hh is not None:
            self.bias_hh = _vector(self.bias_hh, rows)

    @property
    def hidden_size(self) -> int:
        return int(self.weight_hh.shape[1])

    @property
    def input_size(self) -> int:
        return int(self.weight_ih.shape[1])

    @property
    def size(self) -> int:
        return self.hidden_size


@dataclass(eq=False)
class Readout(Node):
    """Decides a class from its input over the whole sample.

    spike_count: argmax_j sum_t s_j[t]; membrane_max: argmax_j max_t x_j[t];
    last: argmax_j x_j[T-1]. Ties go to the lowest index. Output per step = its input.
    """

    kind: ClassVar[str] = "Readout"
    width: int
    mode: str = "spike_count"

    @property
    def size(self) -> int:
        return int(self.width)


@dataclass(eq=False)
class Output(Node):
    """Graph output of ``width`` channels (passes its input through)."""

    kind: ClassVar[str] = "Output"
    width: int

    @property
    def size(self) -> int:
        return int(self.width)


NODE_TYPES: dict[str, type[Node]] = {
    cls.kind: cls for cls in (Input, Dense, Conv, LIF, LSTM, Readout, Output)
}
STATEFUL = (LIF, LSTM)
LINEAR = (Dense, Conv)   # stateless linear maps: y[t] = A x[t] (+ b)

__all__ = [
    "Node", "Input", "Dense", "Conv", "LINEAR", "LIF", "LSTM", "Readout", "Output", "NODE_TYPES", "STATEFUL",
    "RESETS", "DISCRETISATIONS", "BIAS_PLACEMENTS", "READOUT_MODES", "INPUT_KINDS", "FIRE_TESTS",
]
