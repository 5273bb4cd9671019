"""torch modules that compute exactly what the IR graph means, written so the legacy ONNX exporter
traces them into plain, TensorRT-friendly operators (MatMul, Add, Mul, Greater, Cast, Where,
Concat, Slice, Conv + Reshape for convolutions; the native LSTM op for whole-sequence LSTMs).

Per LIF population and step (the reference simulator's equations, in its order):
    I = alpha*I + sum(in) (+b);  V = beta*V + I (+b);  V = 0 while ref > 0 (ref -= 1);
    s = V > theta;  V <- 0 | V - theta where s;  ref <- refractory - 1 where s
An edge with delay d delivers its source's output of step t - d (zeros before t = 0).

* ``UnrolledModel``   — graphs with LIF populations: the whole sample, T fixed, unrolled in Python
  (so the export has no loop operator); Dense maps outside cycles run once over all steps, only
  cycles and LIF populations are stepped.  forward(x (B, T, C)) -> (score (B, n), outputs (B, T, n)).
* ``WholeSequenceModel`` — graphs without LIF (LSTM classifiers): each node over the whole
  sequence (``nn.LSTM`` -> ONNX ``LSTM``), dynamic batch and time. forward(x) -> score (B, n).
* ``StepModel`` — one time step of any graph with its state explicit: LIF (I, V, refractory
  counter), LSTM (h, c) and, for every (node, port) read through a delay, its last D outputs.
  forward(x_t (B, C), *state) -> (y_t (B, n), *next_state).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

from snncc.ir.nodes import LIF, LINEAR, LSTM, Conv, Dense, Input
from snncc.targets.jetson.plan import GraphPlan


def _t(a, dtype=torch.float32) -> torch.Tensor:
    return torch.as_tensor(np.asarray(a, dtype=np.float64), dtype=dtype)


class NodeParams(nn.Module):
    """The graph's parameters as float32 buffers (``fp16_step_model`` rounds them to float16 values)."""

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
            elif isinstance(op, Conv):
                self.register_buffer(f"{k}_w", _t(op.weight))
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


def _same(x: torch.Tensor) -> torch.Tensor:
    return x


def round_fp16(x: torch.Tensor) -> torch.Tensor:
    """Round a float32 tensor to the nearest float16 value (kept in float32)."""
    return x.half().float()


def dense(params: NodeParams, name: str, x: torch.Tensor, q=_same) -> torch.Tensor:
    """y = x @ W^T (+ b)."""
    y = q(x @ params.get(name, "w"))
    b = params.get(name, "b")
    return y if b is None else q(y + b)


def conv(params: NodeParams, name: str, op: Conv, x: torch.Tensor, q=_same) -> torch.Tensor:
    """(..., C*prod(spatial)) -> reshape (-1, C, *spatial) -> ONNX Conv -> (..., size), C order."""
    fn = (F.conv1d, F.conv2d, F.conv3d)[op.spatial_dims - 1]
    lead = x.shape[:-1]
    y = fn(x.reshape((-1,) + op.in_shape), params.get(name, "w"), params.get(name, "b"), stride=op.stride,
           padding=op.padding, dilation=op.dilation, groups=op.groups)
    return q(y.reshape(tuple(lead) + (op.size,)))


def linear(params: NodeParams, name: str, op, x: torch.Tensor, q=_same) -> torch.Tensor:
    """A Dense or Conv node."""
    return conv(params, name, op, x, q) if isinstance(op, Conv) else dense(params, name, x, q)


_COUNTED = object()   # lif_step's default hold: the refractory counter ``ref``


def lif_step(params: NodeParams, name: str, op: LIF, i_syn, v, ref, drive, q=_same, held=_COUNTED):
    """One step of a LIF population; returns (I, V after reset, ref, spikes, fired).

    I <- alpha I + drive (+ bias) ; V <- beta V + I (+ bias) ; V <- 0 while held ; spike if V > theta,
    then V <- 0 (zero reset) or V - theta (subtract). ``q`` rounds every arithmetic result (identity,
    or ``round_fp16`` for fp16 emulation). ``held`` is counted in ``ref`` (held while ref > 0) unless
    the caller passes the hold mask itself: with a refractory period of 2 (the SpyTorch order) a
    neuron is held exactly in the step after a spike, so the previous step's ``fired`` (None before
    the first step) replaces the counter in unrolled graphs.
    """
    i_syn = q(q(params.get(name, "alpha") * i_syn) + drive)
    bias = params.get(name, "bias")
    if bias is not None and op.bias_placement == "current":
        i_syn = q(i_syn + bias)
    v = q(q(params.get(name, "beta") * v) + i_syn)
    if bias is not None and op.bias_placement == "voltage":
        v = q(v + bias)
    counted = op.refractory > 1 and held is _COUNTED
    if counted:
        held = ref > 0
        ref = torch.where(held, ref - 1, ref)
    if op.refractory > 1 and held is not None:
        v = torch.where(held, torch.zeros((), dtype=v.dtype), v)
    theta = params.get(name, "theta")
    fired = v > theta
    spikes = fired.to(v.dtype)
    if op.reset == "zero":
        v_after = torch.where(fired, torch.zeros((), dtype=v.dtype), v)
    else:
        v_after = torch.where(fired, q(v - theta), v)
    if counted:
        ref = torch.where(fired, torch.full((), float(op.refractory - 1), dtype=ref.dtype), ref)
    return i_syn, v_after, ref, spikes, fired


def lstm_cell(params: NodeParams, name: str, hidden: int, h, c, x, q=_same):
    """PyTorch's LSTM cell, gate order i, f, g, o."""
    gates = q(q(q(x @ params.get(name, "wih")) + q(h @ params.get(name, "whh"))) + params.get(name, "b"))
    i = q(torch.sigmoid(gates[..., :hidden]))
    f = q(torch.sigmoid(gates[..., hidden:2 * hidden]))
    gg = q(torch.tanh(gates[..., 2 * hidden:3 * hidden]))
    o = q(torch.sigmoid(gates[..., 3 * hidden:]))
    c = q(q(f * c) + q(i * gg))
    return q(o * q(torch.tanh(c))), c


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


def components(plan: GraphPlan) -> list[list[str]]:
    """Strongly connected components of the graph (all edges), in dependency order; the nodes of
    each in the zero-delay evaluation order. A component with a cycle must be stepped as a whole;
    anything else can be computed for all steps at once (Dense, pass-through) or looped alone (LIF)."""
    g = plan.graph
    rank = {n: i for i, n in enumerate(plan.order)}
    cond = nx.condensation(g.nx)
    members = {c: sorted(cond.nodes[c]["members"], key=rank.__getitem__) for c in cond.nodes}
    order = nx.lexicographical_topological_sort(cond, key=lambda c: rank[members[c][0]])
    return [members[c] for c in order]


class UnrolledModel(nn.Module):
    """The whole sample, T fixed (see module docstring).

    The graph is evaluated component by component: Dense maps outside cycles as one MatMul over
    all steps, a LIF population outside cycles as a loop of element-wise steps, and each cycle
    (e.g. a recurrent population and its recurrent Dense) as a loop over its nodes, every step
    written out (no loop operator in the export).
    """

    def __init__(self, plan: GraphPlan, steps: int):
        super().__init__()
        self.plan, self.steps = plan, int(steps)
        self.params_ = NodeParams(plan)
        self.components = components(plan)
        g = plan.graph
        self.ports = {n: sorted({g.port(n, s) for s in g.successors(n)} | {"spikes"}) for n in g}

    def _drive(self, full, name: str, exclude=()) -> torch.Tensor | None:
        """Sum over predecessors (outside ``exclude``) of their delayed full sequences."""
        g, total = self.plan.graph, None
        for src in g.predecessors(name):
            if src in exclude:
                continue
            v = shift_time(full[(src, g.port(src, name))], g.delay(src, name))
            total = v if total is None else total + v
        return total

    def forward(self, x: torch.Tensor):
        plan, g, p = self.plan, self.plan.graph, self.params_
        full: dict[tuple[str, str], torch.Tensor] = {}
        for comp in self.components:
            name = comp[0]
            op = g.node(name)
            if len(comp) == 1 and not g.nx.has_edge(name, name) and not isinstance(op, (LIF, LSTM)):
                if isinstance(op, Input):
                    full[(name, "spikes")] = tile_copies(x, plan.input_copies)
                elif isinstance(op, LINEAR):
                    full[(name, "spikes")] = linear(p, name, op, self._drive(full, name))
                else:  # Readout, Output: pass through
                    full[(name, "spikes")] = self._drive(full, name)
            else:
                full.update(self._loop(comp, full, x.shape[0], x))
        seq = full[(plan.output_name, "spikes")]
        return score_of(plan.score_mode, seq), seq

    def _loop(self, comp: list[str], full, batch, x) -> dict:
        """Step a component through time; returns its nodes' full sequences. Every per-step tensor
        is (B, 1, n), so a step's input is a Slice of a sequence and the outputs Concat back
        without Unsqueeze nodes."""
        g, p = self.plan.graph, self.params_
        inside = set(comp)
        external = {n: self._drive(full, n, exclude=inside) for n in comp}
        hist: dict[tuple[str, str], list[torch.Tensor]] = {(n, port): [] for n in comp for port in self.ports[n]}
        state: dict[str, list] = {}
        for n in comp:
            op = g.node(n)
            if isinstance(op, LIF):
                state[n] = [x.new_zeros((batch, 1, op.n)), x.new_zeros((batch, 1, op.n)),
                            x.new_zeros((batch, 1, op.n)), None]
            elif isinstance(op, LSTM):
                state[n] = [x.new_zeros((batch, 1, op.hidden_size)), x.new_zeros((batch, 1, op.hidden_size))]
        for t in range(self.steps):
            for n in comp:
                op = g.node(n)
                total = external[n][:, t:t + 1] if external[n] is not None else None
                for src in g.predecessors(n):
                    if src not in inside:
                        continue
                    d = g.delay(src, n)
                    if t - d < 0:
                        continue
                    v = hist[(src, g.port(src, n))][t - d]
                    total = v if total is None else total + v
                if total is None:
                    total = x.new_zeros((batch, 1, _in_width(op)))
                if isinstance(op, LINEAR):
                    hist[(n, "spikes")].append(linear(p, n, op, total))
                elif isinstance(op, LIF):
                    i_syn, v, ref, fired_before = state[n]
                    hold = {"held": fired_before} if op.refractory == 2 else {}   # the mask is cheaper to unroll
                    i_syn, v, ref, s, fired = lif_step(p, n, op, i_syn, v, ref, total, **hold)
                    state[n] = [i_syn, v, ref, fired]
                    hist[(n, "spikes")].append(s)
                    if "voltage" in self.ports[n]:
                        hist[(n, "voltage")].append(v)
                elif isinstance(op, LSTM):
                    h, c = state[n]
                    h, c = lstm_cell(p, n, op.hidden_size, h, c, total)
                    state[n] = [h, c]
                    hist[(n, "spikes")].append(h)
                else:
                    hist[(n, "spikes")].append(total)
        return {key: torch.cat(seq, dim=1) for key, seq in hist.items()}


def _in_width(op) -> int:
    if isinstance(op, LINEAR):
        return op.in_size
    if isinstance(op, LSTM):
        return op.input_size
    return op.size


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
            if isinstance(op, LINEAR):
                full[name] = linear(p, name, op, total)
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
        self.q = _same

    def initial_state(self, batch: int, dtype=torch.float32) -> list[torch.Tensor]:
        """Distinct zero tensors (never one object reused: the exporters merge those)."""
        return [torch.zeros((batch, *s.shape), dtype=dtype) for s in self.slots]

    def forward(self, x_t: torch.Tensor, *states: torch.Tensor):
        plan, g, p, q = self.plan, self.plan.graph, self.params_, self.q
        st = {(s.node, s.what): v for s, v in zip(self.slots, states)}
        cur: dict[tuple[str, str], torch.Tensor] = {}
        nxt: dict[tuple[str, str], torch.Tensor] = {}
        for name in plan.order:
            op = g.node(name)
            if name == plan.input_name:
                cur[(name, "spikes")] = tile_copies(x_t, plan.input_copies)
                continue
            total = None
            for src in g.predecessors(name):
                d, port = g.delay(src, name), g.port(src, name)
                v = cur[(src, port)] if d == 0 else st[(src, f"hist:{port}")][:, d - 1]
                total = v if total is None else q(total + v)
            if isinstance(op, LINEAR):
                cur[(name, "spikes")] = linear(p, name, op, total, q)
            elif isinstance(op, LIF):
                ref = st.get((name, "ref"))
                if ref is None:
                    ref = st[(name, "V")]  # unused when refractory == 1
                i_syn, v, ref, s, _ = lif_step(p, name, op, st[(name, "I")], st[(name, "V")], ref, total, q)
                nxt[(name, "I")], nxt[(name, "V")] = i_syn, v
                if op.refractory > 1:
                    nxt[(name, "ref")] = ref
                cur[(name, "spikes")], cur[(name, "voltage")] = s, v
            elif isinstance(op, LSTM):
                h, c = lstm_cell(p, name, op.hidden_size, st[(name, "h")], st[(name, "c")], total, q)
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


def fp16_step_model(plan: GraphPlan) -> StepModel:
    """The step model with float16 weights and every arithmetic result rounded to float16
    (float32 accumulation inside a matrix product, as TensorRT's fp16 kernels do)."""
    model = StepModel(plan)
    with torch.no_grad():
        for buf in model.params_.buffers():
            buf.copy_(round_fp16(buf))
    model.q = round_fp16
    return model


def run_steps(model: StepModel, x: torch.Tensor) -> torch.Tensor:
    """Drive the step model over x (B, T, C) from zero state in torch; returns (B, T, n)."""
    states = model.initial_state(x.shape[0], x.dtype)
    ys = []
    for t in range(x.shape[1]):
        y, *states = model(x[:, t], *states)
        ys.append(y)
    return torch.stack(ys, dim=1)
