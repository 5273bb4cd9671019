"""torch modules that compute exactly what the IR graph means, written so the legacy ONNX exporter
traces them into plain, TensorRT-friendly operators (MatMul, Add, Mul, Greater, Cast, Where,
Concat, Slice; the native LSTM op for whole-sequence LSTMs).

Per LIF population and step (the reference simulator's equations, in its order):
    I = alpha*I + sum(in) (+b);  V = beta*V + I (+b);  V = 0 while ref > 0 (ref -= 1);
    s = V > theta;  V <- 0 | V - theta where s;  ref <- refractory - 1 where s
An edge with delay d delivers its source's output of step t - d (zeros before t = 0).

* ``UnrolledModel``   — graphs with LIF populations: the whole sample, T fixed, unrolled in Python
  (so the export has no loop operator); parts fed only by the input through Dense maps are computed
  for all steps at once.  forward(x (B, T, C)) -> (score (B, n), output sequence (B, T, n)).
* ``WholeSequenceModel`` — graphs without LIF (LSTM classifiers): each node over the whole
  sequence (``nn.LSTM`` -> ONNX ``LSTM``), dynamic batch and time. forward(x) -> score (B, n).
* ``StepModel`` — one time step of any graph with its state explicit: LIF (I, V, refractory
  counter), LSTM (h, c) and, for every (node, port) read through a delay, its last D outputs.
  forward(x_t (B, C), *state) -> (y_t (B, n), *next_state).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from snncc.ir.nodes import LIF, LSTM, Dense, Input
from snncc.targets.jetson.plan import GraphPlan


def _t(a, dtype=torch.float32) -> torch.Tensor:
    return torch.as_tensor(np.asarray(a, dtype=np.float64), dtype=dtype)


class NodeParams(nn.Module):
    """The graph's parameters as buffers (float32; ``.half()`` casts them for fp16 emulation)."""

    def __init__(self, plan: GraphPlan):
        super().__init__()
        g = plan.graph
        self.key = {}
        for i, (name, op) in enumerate(g.items()):
            k = f"n{i}"
            self.key[name] = k
            if isinstance(op, Dense):
                self.register_buffer(f"{k}_w", _t(op.weight.T.copy()))
                if op.bias is not None:
                    self.register_buffer(f"{k}_b", _t(op.bias))
            elif isinstance(op, LIF):
                alpha, beta = op.decays(g.dt)
                self.register_buffer(f"{k}_alpha", _t(alpha))
                self.register_buffer(f"{k}_beta", _t(beta))
                self.register_buffer(f"{k}_theta", _t(op.threshold))
                if op.bias is not None:
                    self.register_buffer(f"{k}_bias", _t(op.bias))
            elif isinstance(op, LSTM):
                b = np.zeros(op.weight_ih.shape[0])
                for extra in (op.bias_ih, op.bias_hh):
                    if extra is not None:
                        b = b + extra
                self.register_buffer(f"{k}_wih", _t(op.weight_ih.T.copy()))
                self.register_buffer(f"{k}_whh", _t(op.weight_hh.T.copy()))
                self.register_buffer(f"{k}_b", _t(b))

    def get(self, name: str, what: str) -> torch.Tensor | None:
        return getattr(self, f"{self.key[name]}_{what}", None)


def dense(params: NodeParams, name: str, x: torch.Tensor) -> torch.Tensor:
    """y = x @ W^T (+ b)."""
    y = x @ params.get(name, "w")
    b = params.get(name, "b")
    return y if b is None else y + b


def lif_step(params: NodeParams, name: str, op: LIF, i_syn, v, ref, drive):
    """One step of a LIF population; returns (I, V after reset, ref, spikes)."""
    i_syn = params.get(name, "alpha") * i_syn + drive
    bias = params.get(name, "bias")
    if bias is not None and op.bias_placement == "current":
        i_syn = i_syn + bias
    v = params.get(name, "beta") * v + i_syn
    if bias is not None and op.bias_placement == "voltage":
        v = v + bias
    if op.refractory > 1:
        held = ref > 0
        v = torch.where(held, torch.zeros((), dtype=v.dtype), v)
        ref = torch.where(held, ref - 1, ref)
    theta = params.get(name, "theta")
    fired = v > theta
    spikes = fired.to(v.dtype)
    if op.reset == "zero":
        v_after = torch.where(fired, torch.zeros((), dtype=v.dtype), v)
    else:
        v_after = torch.where(fired, v - theta, v)
    if op.refractory > 1:
        ref = torch.where(fired, torch.full((), float(op.refractory - 1), dtype=ref.dtype), ref)
    return i_syn, v_after, ref, spikes


def lstm_cell(params: NodeParams, name: str, hidden: int, h, c, x):
    """PyTorch's LSTM cell, gate order i, f, g, o."""
    gates = x @ params.get(name, "wih") + h @ params.get(name, "whh") + params.get(name, "b")
    i = torch.sigmoid(gates[:, :hidden])
    f = torch.sigmoid(gates[:, hidden:2 * hidden])
    gg = torch.tanh(gates[:, 2 * hidden:3 * hidden])
    o = torch.sigmoid(gates[:, 3 * hidden:])
    c = f * c + i * gg
    return o * torch.tanh(c), c


def tile_copies(x: torch.Tensor, k: int) -> torch.Tensor:
    """The authors' ``x.tile((k,))``: k copies side by side on the channel axis."""
    return x if k == 1 else torch.cat([x] * k, dim=-1)


def shift_time(x: torch.Tensor, d: int) -> torch.Tensor:
    """x[:, t - d] along axis 1, zeros for t < d (works for a dynamic T)."""
    if d == 0:
        return x
    return F.pad(x, (0, 0, d, 0))[:, :-d]


def score_of(mode: str | None, seq: torch.Tensor) -> torch.Tensor:
    """The readout's score from (B, T, n): spike count, max over time, or the last step."""
    if mode == "membrane_max":
        return seq.max(dim=1).values
    if mode == "last":
        return seq[:, -1]
    return seq.sum(dim=1)


def _static_nodes(plan: GraphPlan) -> list[str]:
    """Nodes whose output depends only on the input through Dense maps (in evaluation order)."""
    g = plan.graph
    static: list[str] = []
    for name in plan.order:
        op = g.node(name)
        if isinstance(op, Input) or (isinstance(op, Dense) and all(p in static for p in g.predecessors(name))):
            static.append(name)
    return static


class UnrolledModel(nn.Module):
    """The whole sample, T fixed, every step written out (see module docstring)."""

    def __init__(self, plan: GraphPlan, steps: int):
        super().__init__()
        self.plan, self.steps = plan, int(steps)
        self.params_ = NodeParams(plan)
        self.static = _static_nodes(plan)

    def forward(self, x: torch.Tensor):
        plan, g, p = self.plan, self.plan.graph, self.params_
        x = tile_copies(x, plan.input_copies)
        batch = x.shape[0]
        full: dict[str, torch.Tensor] = {}
        for name in self.static:
            if name == plan.input_name:
                full[name] = x
            else:
                (src,) = g.predecessors(name)
                full[name] = dense(p, name, shift_time(full[src], g.delay(src, name)))
        dynamic = [n for n in plan.order if n not in self.static]
        static_drive = {}
        for name in dynamic:
            preds = [q for q in g.predecessors(name) if q in self.static]
            if preds:
                total = None
                for q in preds:
                    v = shift_time(full[q], g.delay(q, name))
                    total = v if total is None else total + v
                static_drive[name] = total
        hist: dict[tuple[str, str], list[torch.Tensor]] = {}
        state: dict[str, list[torch.Tensor]] = {}
        for name in dynamic:
            op = g.node(name)
            if isinstance(op, LIF):
                z = x.new_zeros((batch, op.n))
                state[name] = [z, x.new_zeros((batch, op.n)), x.new_zeros((batch, op.n))]
            elif isinstance(op, LSTM):
                state[name] = [x.new_zeros((batch, op.hidden_size)), x.new_zeros((batch, op.hidden_size))]
            hist[(name, "spikes")] = []
            hist[(name, "voltage")] = []

        def in_width(op) -> int:
            if isinstance(op, Dense):
                return op.in_size
            if isinstance(op, LSTM):
                return op.input_size
            return op.size

        for t in range(self.steps):
            for name in dynamic:
                op = g.node(name)
                total = static_drive[name][:, t] if name in static_drive else None
                for q in g.predecessors(name):
                    if q in self.static:
                        continue
                    d = g.delay(q, name)
                    if t - d < 0:
                        continue
                    v = hist[(q, g.port(q, name))][t - d]
                    total = v if total is None else total + v
                if total is None:
                    total = x.new_zeros((batch, in_width(op)))
                if isinstance(op, Dense):
                    out = dense(p, name, total)
                    hist[(name, "spikes")].append(out)
                elif isinstance(op, LIF):
                    i_syn, v, ref = state[name]
                    i_syn, v, ref, s = lif_step(p, name, op, i_syn, v, ref, total)
                    state[name] = [i_syn, v, ref]
                    hist[(name, "spikes")].append(s)
                    hist[(name, "voltage")].append(v)
                elif isinstance(op, LSTM):
                    h, c = state[name]
                    h, c = lstm_cell(p, name, op.hidden_size, h, c, total)
                    state[name] = [h, c]
                    hist[(name, "spikes")].append(h)
                else:
                    hist[(name, "spikes")].append(total)
        out_name = plan.output_name
        seq = full[out_name] if out_name in full else torch.stack(hist[(out_name, "spikes")], dim=1)
        return score_of(plan.score_mode, seq), seq


class WholeSequenceModel(nn.Module):
    """LIF-free graphs over the whole sequence with dynamic batch and time (``nn.LSTM``)."""

    def __init__(self, plan: GraphPlan):
        super().__init__()
        self.plan = plan
        self.params_ = NodeParams(plan)
        self.lstms = nn.ModuleDict()
        for name, op in plan.graph.items():
            if isinstance(op, LSTM):
                m = nn.LSTM(op.input_size, op.hidden_size, batch_first=True)
                with torch.no_grad():
                    m.weight_ih_l0.copy_(_t(op.weight_ih))
                    m.weight_hh_l0.copy_(_t(op.weight_hh))
                    m.bias_ih_l0.copy_(_t(op.bias_ih if op.bias_ih is not None else np.zeros(4 * op.hidden_size)))
                    m.bias_hh_l0.copy_(_t(op.bias_hh if op.bias_hh is not None else np.zeros(4 * op.hidden_size)))
                m.requires_grad_(False)
                self.lstms[self.params_.key[name]] = m

    def forward(self, x: torch.Tensor):
        plan, g, p = self.plan, self.plan.graph, self.params_
        full: dict[str, torch.Tensor] = {}
        for name in plan.order:
            op = g.node(name)
            if name == plan.input_name:
                full[name] = tile_copies(x, plan.input_copies)
                continue
            total = None
            for q in g.predecessors(name):
                v = shift_time(full[q], g.delay(q, name))
                total = v if total is None else total + v
            if isinstance(op, Dense):
                full[name] = dense(p, name, total)
            elif isinstance(op, LSTM):
                full[name] = self.lstms[p.key[name]](total)[0]
            else:
                full[name] = total
        return score_of(plan.score_mode, full[plan.output_name])


@dataclass(frozen=True)
class StateSlot:
    """One state tensor of the step model: (B, *shape)."""

    node: str
    what: str          # I | V | ref | h | c | hist:spikes | hist:voltage
    shape: tuple[int, ...]

    @property
    def input_name(self) -> str:
        return f"state.{self.node}.{self.what.replace(':', '.')}"

    @property
    def output_name(self) -> str:
        return f"next.{self.node}.{self.what.replace(':', '.')}"


def state_slots(plan: GraphPlan) -> list[StateSlot]:
    g = plan.graph
    slots: list[StateSlot] = []
    for name, op in g.items():
        if isinstance(op, LIF):
            slots += [StateSlot(name, "I", (op.n,)), StateSlot(name, "V", (op.n,))]
            if op.refractory > 1:
                slots.append(StateSlot(name, "ref", (op.n,)))
        elif isinstance(op, LSTM):
            slots += [StateSlot(name, "h", (op.hidden_size,)), StateSlot(name, "c", (op.hidden_size,))]
    for (node, port), depth in plan.history.items():
        slots.append(StateSlot(node, f"hist:{port}", (depth, g.node(node).size)))
    return slots


class StepModel(nn.Module):
    """One time step with the state explicit (see module docstring)."""

    def __init__(self, plan: GraphPlan):
        super().__init__()
        self.plan = plan
        self.params_ = NodeParams(plan)
        self.slots = state_slots(plan)

    def initial_state(self, batch: int, dtype=torch.float32) -> list[torch.Tensor]:
        """Distinct zero tensors (never one object reused: the exporters merge those)."""
        return [torch.zeros((batch, *s.shape), dtype=dtype) for s in self.slots]

    def forward(self, x_t: torch.Tensor, *states: torch.Tensor):
        plan, g, p = self.plan, self.plan.graph, self.params_
        st = {(s.node, s.what): v for s, v in zip(self.slots, states)}
        cur: dict[tuple[str, str], torch.Tensor] = {}
        nxt: dict[tuple[str, str], torch.Tensor] = {}
        for name in plan.order:
            op = g.node(name)
            if name == plan.input_name:
                cur[(name, "spikes")] = tile_copies(x_t, plan.input_copies)
                continue
            total = None
            for q in g.predecessors(name):
                d, port = g.delay(q, name), g.port(q, name)
                v = cur[(q, port)] if d == 0 else st[(q, f"hist:{port}")][:, d - 1]
                total = v if total is None else total + v
            if isinstance(op, Dense):
                cur[(name, "spikes")] = dense(p, name, total)
            elif isinstance(op, LIF):
                ref = st.get((name, "ref"))
                if ref is None:
                    ref = st[(name, "V")]  # unused when refractory == 1
                i_syn, v, ref, s = lif_step(p, name, op, st[(name, "I")], st[(name, "V")], ref, total)
                nxt[(name, "I")], nxt[(name, "V")] = i_syn, v
                if op.refractory > 1:
                    nxt[(name, "ref")] = ref
                cur[(name, "spikes")], cur[(name, "voltage")] = s, v
            elif isinstance(op, LSTM):
                h, c = lstm_cell(p, name, op.hidden_size, st[(name, "h")], st[(name, "c")], total)
                nxt[(name, "h")], nxt[(name, "c")] = h, c
                cur[(name, "spikes")] = h
            else:
                cur[(name, "spikes")] = total
        for (node, port), depth in plan.history.items():
            newest = cur[(node, port)].unsqueeze(1)
            old = st[(node, f"hist:{port}")]
            nxt[(node, f"hist:{port}")] = newest if depth == 1 else torch.cat([newest, old[:, : depth - 1]], dim=1)
        y = cur[(plan.output_name, "spikes")]
        return (y, *[nxt[(s.node, s.what)] for s in self.slots])


def run_steps(model: StepModel, x: torch.Tensor) -> torch.Tensor:
    """Drive the step model over x (B, T, C) from zero state in torch; returns (B, T, n)."""
    states = model.initial_state(x.shape[0], x.dtype)
    ys = []
    for t in range(x.shape[1]):
        y, *states = model(x[:, t], *states)
        ys.append(y)
    return torch.stack(ys, dim=1)
