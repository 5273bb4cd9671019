"""The reference simulator: the single definition of what an IR graph computes.

Batched and vectorised in torch, float32 or float64. One time step t evaluates every node in
the topological order of the zero-delay edges; an edge with delay d delivers its source's
output of step t - d (zeros before t = 0). Node equations are those in ``snncc.ir.nodes``:

    LIF:  I = alpha*I + sum(in) (+b_I);  V = beta*V + I (+b_V);  V = 0 while refractory;
          s = V > theta;  V <- 0 | V - theta where s;  refractory counter <- r - 1 where s
          (spike rule max_spikes m / fire_test: s = min(m, floor(V/theta)) on V >= theta, or
          min(m, ceil(V/theta) - 1) on V > theta; V <- 0 | V - s*theta where s > 0)
    LSTM: PyTorch's cell, gate order i, f, g, o

    Dense: y = W x (+b);  Conv: PyTorch's convNd on the C-order flattened map (``snncc.ir.conv``)

Parts of the graph fed only by inputs through linear nodes (Dense, Conv; no state) are computed
for the whole sequence at once before the time loop.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx
import numpy as np
import torch

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.conv import conv_apply
from snncc.ir.nodes import LIF, LINEAR, LSTM, Conv, Dense, Input, Output, Readout

RECORD_CHOICES = ("outputs", "spikes", "all")


@dataclass
class SimulationResult:
    """What a simulation produced. Tensors are (B, T, n) unless stated."""

    outputs: dict[str, torch.Tensor]
    spikes: dict[str, torch.Tensor] = field(default_factory=dict)
    voltage: dict[str, torch.Tensor] = field(default_factory=dict)
    current: dict[str, torch.Tensor] = field(default_factory=dict)
    hidden: dict[str, torch.Tensor] = field(default_factory=dict)
    readout: torch.Tensor | None = None      # (B, n): the score the Readout takes argmax of
    prediction: torch.Tensor | None = None   # (B,) int64, ties to the lowest index

    @property
    def output(self) -> torch.Tensor:
        """The single Output node's (B, T, n) tensor."""
        if len(self.outputs) != 1:
            raise SnnccError(f"graph has {len(self.outputs)} outputs; name one", field="outputs")
        return next(iter(self.outputs.values()))


def as_input_tensor(x, dtype: torch.dtype) -> torch.Tensor:
    """Accept (T, C) or (B, T, C) numpy/torch data; return (B, T, C) of ``dtype``."""
    t = torch.as_tensor(np.asarray(x) if not isinstance(x, torch.Tensor) else x)
    if t.dim() == 2:
        t = t.unsqueeze(0)
    if t.dim() != 3:
        raise SnnccError(f"input must have shape (T, C) or (B, T, C), got {tuple(t.shape)}", field="input")
    return t.to(dtype)


def spike_count(v: torch.Tensor, theta: torch.Tensor, max_spikes: int, fire_test: str) -> torch.Tensor:
    """Spikes in one step under a LIF's spike rule: how many times ``v`` passes ``fire_test`` theta while
    theta is subtracted, at most ``max_spikes`` (theta > 0; +inf never fires)."""
    ratio = v / theta
    n = torch.floor(ratio) if fire_test == ">=" else torch.ceil(ratio) - 1.0
    return torch.clamp(n, min=0.0, max=float(max_spikes))


def _schedule(g: Graph) -> list[str]:
    zero = nx.DiGraph()
    zero.add_nodes_from(g.nx.nodes)
    zero.add_edges_from((u, v) for u, v, d, _ in g.edges() if d == 0)
    return list(nx.lexicographical_topological_sort(zero, key=list(g.nx.nodes).index))


def _static_nodes(g: Graph) -> set[str]:
    """Nodes whose output depends only on inputs through stateless linear maps."""
    static: set[str] = set()
    for name in nx.topological_sort(g.nx.subgraph([n for n, op in g.items() if isinstance(op, (Input,) + LINEAR)])):
        op = g.node(name)
        if isinstance(op, Input) or all(p in static for p in g.predecessors(name)):
            static.add(name)
    return static


SPARSE_MIN_SIZE = 1 << 20      # Dense weights this large and at most a quarter nonzero run as sparse
SPARSE_MAX_DENSITY = 0.25      # products (same sums, another summation order)


def _weight_tensor(op, dtype: torch.dtype) -> torch.Tensor:
    w = torch.as_tensor(op.weight, dtype=dtype)
    if isinstance(op, Dense) and w.numel() >= SPARSE_MIN_SIZE and \
            int(torch.count_nonzero(w)) <= SPARSE_MAX_DENSITY * w.numel():
        import warnings

        with warnings.catch_warnings():   # torch calls its sparse CSR support beta; products are plain
            warnings.simplefilter("ignore", UserWarning)
            return w.to_sparse_csr()
    return w


def _shift(x: torch.Tensor, d: int) -> torch.Tensor:
    """x[:, t - d] along time, zeros for t < d."""
    if d == 0:
        return x
    out = torch.zeros_like(x)
    if d < x.shape[1]:
        out[:, d:] = x[:, :-d]
    return out


class _Runner:
    def __init__(self, g: Graph, dtype: torch.dtype, record: str):
        self.g, self.dtype, self.record = g, dtype, record
        self.order = _schedule(g)
        self.static = _static_nodes(g)
        self.t_ = {}  # torch copies of parameters
        for name, op in g.items():
            if isinstance(op, LINEAR):
                self.t_[name] = (
                    _weight_tensor(op, dtype),
                    None if op.bias is None else torch.as_tensor(op.bias, dtype=dtype),
                )
            elif isinstance(op, LIF):
                alpha, beta = op.decays(g.dt)
                self.t_[name] = tuple(
                    torch.as_tensor(a, dtype=dtype)
                    for a in (alpha, beta, op.threshold, op.bias if op.bias is not None else np.zeros(op.n))
                )
            elif isinstance(op, LSTM):
                b = np.zeros(op.weight_ih.shape[0])
                for extra in (op.bias_ih, op.bias_hh):
                    if extra is not None:
                        b = b + extra
                self.t_[name] = (
                    torch.as_tensor(op.weight_ih, dtype=dtype),
                    torch.as_tensor(op.weight_hh, dtype=dtype),
                    torch.as_tensor(b, dtype=dtype),
                )

    def linear(self, name: str, x: torch.Tensor) -> torch.Tensor:
        """A Dense or Conv node applied to (..., in) -> (..., out)."""
        op = self.g.node(name)
        w, b = self.t_[name]
        if isinstance(op, Conv):
            return conv_apply(op, x, w, b)
        if w.layout == torch.sparse_csr:    # y^T = W x^T, W sparse (a folded convolution)
            flat = x.reshape(-1, x.shape[-1])
            y = (w @ flat.T).T.reshape(tuple(x.shape[:-1]) + (w.shape[0],))
        else:
            y = x @ w.T
        return y if b is None else y + b

    def run(self, inputs: dict[str, torch.Tensor]) -> SimulationResult:
        g = self.g
        batch, steps = next(iter(inputs.values())).shape[:2]
        full: dict[str, torch.Tensor] = {}
        for name in self.order:
            if name not in self.static:
                continue
            op = g.node(name)
            if isinstance(op, Input):
                full[name] = inputs[name]
            else:
                (src,) = g.predecessors(name)
                full[name] = self.linear(name, _shift(full[src], g.delay(src, name)))

        dynamic = [n for n in self.order if n not in self.static]
        # per-step histories of dynamic nodes' outputs: hist[(node, port)][t]
        hist: dict[tuple[str, str], list[torch.Tensor]] = {}
        state: dict[str, dict[str, torch.Tensor]] = {}
        static_drive: dict[str, torch.Tensor] = {}
        for name in dynamic:
            op = g.node(name)
            ports = {g.port(name, s) for s in g.successors(name)} | {"spikes"}
            for port in ports:
                hist[(name, port)] = []
            if isinstance(op, LIF):
                z = torch.zeros(batch, op.n, dtype=self.dtype)
                state[name] = {"I": z, "V": z.clone(), "ref": torch.zeros(batch, op.n, dtype=torch.int32)}
            elif isinstance(op, LSTM):
                z = torch.zeros(batch, op.hidden_size, dtype=self.dtype)
                state[name] = {"h": z, "c": z.clone()}
            static_preds = [p for p in g.predecessors(name) if p in self.static]
            if static_preds and isinstance(op, (LIF, Readout, Output, LSTM) + LINEAR):
                static_drive[name] = sum(_shift(full[p], g.delay(p, name)) for p in static_preds)

        want_state = self.record == "all"
        want_spikes = self.record in ("spikes", "all")

        def fetch(src: str, dst: str, t: int) -> torch.Tensor | None:
            d = g.delay(src, dst)
            if src in self.static:
                return None  # already in static_drive
            if t - d < 0:
                return None
            return hist[(src, g.port(src, dst))][t - d]

        def drive(name: str, t: int, width: int) -> torch.Tensor:
            total = static_drive[name][:, t] if name in static_drive else None
            for p in g.predecessors(name):
                v = fetch(p, name, t)
                if v is not None:
                    total = v if total is None else total + v
            return total if total is not None else torch.zeros(batch, width, dtype=self.dtype)

        per_step: dict[str, dict[str, list[torch.Tensor]]] = {n: {} for n in dynamic}
        ports_of = {n: [p for (m, p) in hist if m == n] for n in dynamic}
        for t in range(steps):
            for name in dynamic:
                op = g.node(name)
                if isinstance(op, LINEAR):
                    out = {"spikes": self.linear(name, drive(name, t, op.in_size))}
                elif isinstance(op, LIF):
                    alpha, beta, theta, bias = self.t_[name]
                    st = state[name]
                    i_new = alpha * st["I"] + drive(name, t, op.n)
                    if op.bias is not None and op.bias_placement == "current":
                        i_new = i_new + bias
                    v_new = beta * st["V"] + i_new
                    if op.bias is not None and op.bias_placement == "voltage":
                        v_new = v_new + bias
                    refractory = st["ref"] > 0
                    v_new = torch.where(refractory, torch.zeros_like(v_new), v_new)
                    ref = torch.where(refractory, st["ref"] - 1, st["ref"])
                    if op.standard_spikes:
                        s = (v_new > theta).to(self.dtype)
                    else:
                        s = spike_count(v_new, theta, op.max_spikes, op.fire_test)
                    fired = s > 0
                    if op.reset == "zero":
                        v_after = torch.where(fired, torch.zeros_like(v_new), v_new)
                    elif op.standard_spikes:
                        v_after = torch.where(fired, v_new - theta, v_new)  # no 0*inf for integrators
                    else:
                        v_after = torch.where(fired, v_new - s * theta, v_new)
                    if op.refractory > 1:
                        ref = torch.where(fired, torch.full_like(ref, op.refractory - 1), ref)
                    st["I"], st["V"], st["ref"] = i_new, v_after, ref
                    out = {"spikes": s, "voltage": v_after}
                    if want_state:
                        per_step[name].setdefault("current", []).append(i_new)
                        per_step[name].setdefault("voltage", []).append(v_after)
                elif isinstance(op, LSTM):
                    w_ih, w_hh, b = self.t_[name]
                    st = state[name]
                    x = drive(name, t, op.input_size)
                    gates = x @ w_ih.T + st["h"] @ w_hh.T + b
                    i, f, gg, o = gates.chunk(4, dim=1)
                    c = torch.sigmoid(f) * st["c"] + torch.sigmoid(i) * torch.tanh(gg)
                    h = torch.sigmoid(o) * torch.tanh(c)
                    st["h"], st["c"] = h, c
                    out = {"spikes": h}
                else:  # Readout, Output: pass the input through
                    out = {"spikes": drive(name, t, op.size)}
                for port in ports_of[name]:
                    hist[(name, port)].append(out[port])

        def stack(seq: list[torch.Tensor]) -> torch.Tensor:
            return torch.stack(seq, dim=1)

        result = SimulationResult(outputs={})
        for name, op in g.items():
            series = full.get(name)
            if series is None and (name, "spikes") in hist:
                series = stack(hist[(name, "spikes")]) if steps else torch.zeros(batch, 0, op.size, dtype=self.dtype)
            if isinstance(op, Output):
                result.outputs[name] = series
            elif isinstance(op, LIF) and (want_spikes or want_state):
                result.spikes[name] = series
                if want_state:
                    result.current[name] = stack(per_step[name]["current"])
                    result.voltage[name] = stack(per_step[name]["voltage"])
            elif isinstance(op, LSTM) and want_state:
                result.hidden[name] = series
            if isinstance(op, Readout):
                if op.mode == "spike_count":
                    score = series.sum(dim=1)
                elif op.mode == "membrane_max":
                    score = series.max(dim=1).values
                else:
                    score = series[:, -1]
                result.readout = score
                result.prediction = torch.argmax(score, dim=1)
        return result


def simulate(
    g: Graph,
    inputs,
    *,
    dtype: torch.dtype = torch.float64,
    record: str = "outputs",
) -> SimulationResult:
    """Run the reference semantics of ``g`` on ``inputs``.

    ``inputs``: an array (T, C) / (B, T, C) for a graph with one Input, or a dict by Input name.
    ``record``: "outputs" (outputs and readout only), "spikes" (+ every LIF's spikes) or "all"
    (+ LIF current and post-reset voltage, LSTM hidden states). Every sample starts from zero state.
    """
    if record not in RECORD_CHOICES:
        raise SnnccError(f"record must be one of {RECORD_CHOICES}", field="record")
    in_names = g.of_kind(Input)
    if not isinstance(inputs, dict):
        if len(in_names) != 1:
            raise SnnccError(f"graph has {len(in_names)} inputs; pass a dict by name", field="inputs")
        inputs = {in_names[0]: inputs}
    tensors: dict[str, torch.Tensor] = {}
    shape = None
    for name in in_names:
        if name not in inputs:
            raise SnnccError("no data given for this input", field=f"input '{name}'")
        x = as_input_tensor(inputs[name], dtype)
        width = g.node(name).size
        if x.shape[2] != width:
            raise SnnccError(f"input has {x.shape[2]} channels, the graph expects {width}", field=f"input '{name}'")
        if not torch.all(torch.isfinite(x)):
            raise SnnccError("input contains NaN or Inf", field=f"input '{name}'")
        if shape is not None and x.shape[:2] != shape:
            raise SnnccError("all inputs must share batch and time sizes", field=f"input '{name}'")
        shape = x.shape[:2]
        tensors[name] = x
    with torch.no_grad():
        return _Runner(g, dtype, record).run(tensors)
