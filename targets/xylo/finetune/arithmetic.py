"""Xylo Audio 2's v2-core arithmetic as a differentiable torch model, for deployment fine-tuning.

The forward pass computes ``emulation.literal.reference_run``'s rules exactly (docs/xylo.md), for specs without
aliases and with thresholds >= 1, in tensors of ``compute_dtype``: float32 on the CPU, float64 elsewhere
(a GPU may round float32 products to TF32). float32 is exact here: every value the chip keeps is an
integer below 2**24 in magnitude (int16 states, 16-bit weights times at most 31 events), and a sum of
deliveries that could pass 2**24 leaves the int16 range first, so ``deliver`` replays it one addition
at a time:

    w_eff = wrap16(w << shift)                                     w: int8 shadows, rounded (straight through)
    Isyn_s[k] = sat16(... sat16(Isyn_s[k] + c_0 w_0k) ... + c_j w_jk)   inputs of step t (no delay), then the
                                                                   hidden events of step t - 1, in index order
    Isyn_s -= decay(Isyn_s, dash_syn_s)      decay(x, d) = x >> d (floor), or sign(x) where that is 0
    dv = sat16(wrap16(-decay(V, dash_mem)) + Isyn_1 + Isyn_2);  dv = sat16(dv + bias);  V = sat16(V + dv)
    n = min(floor(V / theta), cap) where V >= theta, else 0;  V -= n * theta   (multi-spike subtract reset:
                                                                   the chip's loop, cap 31 hidden, 1 output)

Saturation is per addition on the chip; the model adds each step's contributions at once and replays
them one by one (the chip's order) only where a partial sum leaves the int16 range, so the result is
the chip's in every case. Backward: rounding, wrapping and the shift decays pass gradients straight
through (d decay(x, d) / dx = 2**-d), saturation clamps, and the event count uses the fast-sigmoid
surrogate of ``kit.finetuning`` on (V - theta) / theta.

Learnable: the int8 weights of the three matrices, hidden and output thresholds (>= 1) and biases.
Fixed: the bit-shift decays (dash_*), the weight shifts, the synapse layout. The model is the
``DifferentiableArithmetic`` of ``kit.finetuning``; ``export()`` gives the ``XyloSpec``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import torch

from snncc.targets.kit import SnnccError
from snncc.targets.kit.finetuning import StudentRun, floor_ste, round_ste, wrap_ste
from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.spec import XyloSpec

STATE_MIN, STATE_MAX = float(CORE.state_min), float(CORE.state_max)
BITS = CORE.state_bits - 1


class _Events(torch.autograd.Function):
    """n = clamp(floor(v / theta), 0, cap) for theta >= 1 (the chip's loop); surrogate h((v - theta) / u) / u, u the
    neuron's unit: the chip units of one IR threshold (theta itself for a direct neuron; for a single-rule neuron,
    whose threshold carries an offset of about 2**14, its gain)."""

    @staticmethod
    def forward(ctx, v, theta, unit, cap: float, slope: float):
        ctx.save_for_backward(v, theta, unit)
        ctx.slope = slope
        n = torch.div(v, theta, rounding_mode="floor").clamp(0.0, cap)
        return n

    @staticmethod
    def backward(ctx, g):
        v, theta, unit = ctx.saved_tensors
        h = 1.0 / (1.0 + ctx.slope * ((v - theta) / unit).abs()) ** 2 / unit
        gv = g * h
        gt = None
        if ctx.needs_input_grad[1]:
            gt = (-gv).sum_to_size(theta.shape)
        return gv, gt, None, None, None


def events(v: torch.Tensor, theta: torch.Tensor, cap: int, slope: float = 5.0,
           unit: torch.Tensor | None = None) -> torch.Tensor:
    """Events per step with the surrogate on (v - theta) / unit (``unit`` defaults to theta)."""
    return _Events.apply(v, theta, theta.detach() if unit is None else unit, float(cap), float(slope))


def shift_decay(x: torch.Tensor, dash: torch.Tensor) -> torch.Tensor:
    """x >> dash (floor), sign(x) where that is 0; gradient 2**-dash."""
    d = floor_ste(x / 2.0 ** dash)
    return torch.where(d == 0, torch.sign(x).detach(), d)


def compute_dtype(device=None) -> torch.dtype:
    """float32 on the CPU (exact for the chip's integers, module doc; about twice as fast), float64 elsewhere."""
    return torch.float32 if torch.device(device or "cpu").type == "cpu" else torch.float64


def sat16(x: torch.Tensor) -> torch.Tensor:
    return x.clamp(STATE_MIN, STATE_MAX)


def deliver(isyn: torch.Tensor, counts: torch.Tensor, w: torch.Tensor, replay=None,
            w_negative: torch.Tensor | None = None) -> torch.Tensor:
    """sat16 after each addition, in pre-synaptic order: ``isyn`` (B, N, S) + ``counts`` (B, P) events through
    ``w`` (P, N, S). The sum at once where no partial sum can leave the range (bounded by the positive and the
    negative contributions: counts are >= 0), else the additions one by one, over ``counts``' columns in the order
    ``replay`` (default: as they stand; a column left out must have zero weights). ``w_negative``: w's negative
    part, min(w, 0), when the caller keeps it across steps."""
    added = torch.einsum("bp,pns->bns", counts, w)
    with torch.no_grad():
        neg_w = w.detach().clamp(max=0.0) if w_negative is None else w_negative
        negative = torch.einsum("bp,pns->bns", counts, neg_w)
    if _in_range(isyn, added, negative):
        return isyn + added
    return _replay(isyn, counts, w, replay)


def _in_range(isyn: torch.Tensor, added: torch.Tensor, negative: torch.Tensor) -> bool:
    """No partial sum of a delivery leaves int16: isyn plus all negative contributions, and isyn plus all positive
    ones (``added`` - ``negative``; exact: integers), stay in range."""
    with torch.no_grad():
        low = isyn + negative
        high = low + (added - 2.0 * negative)
        return bool((high <= STATE_MAX).all()) and bool((low >= STATE_MIN).all())


def _replay(isyn: torch.Tensor, counts: torch.Tensor, w: torch.Tensor, order=None) -> torch.Tensor:
    """The additions one by one, in pre-synaptic order (the columns of ``counts`` in ``order``, default as they
    stand), sat16 after each (the chip's loop)."""
    out = isyn
    for j in range(counts.shape[1]) if order is None else order:
        out = sat16(out + counts[:, j, None, None] * w[j])
    return out


def recurrent_blocks(w_rec: torch.Tensor) -> list[np.ndarray]:
    """The hidden neurons split into the connected components of the recurrent weights (N, N, S) != 0, each
    sorted (a replicated network's copies: one block each). No weight joins two blocks, so each block's
    currents take only the inputs and its own neurons' events."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components

    joined = (w_rec.detach() != 0).any(-1).cpu().numpy()
    count, label = connected_components(csr_matrix(joined), directed=True, connection="weak")
    return [np.flatnonzero(label == k) for k in range(count)]


class _Blocks:
    """The hidden neurons reordered so that each recurrent block (``recurrent_blocks``) is contiguous, each kept
    in index order: a step's currents are delivered one block at a time, each taking the inputs and its own
    neurons' events only, with the same sums and the same replay order per neuron as over the whole network
    (sources outside a block add nothing to it). One block: the identity, delivered whole."""

    def __init__(self, blocks: list[np.ndarray], device):
        self.order = np.concatenate(blocks)
        self.single = len(blocks) == 1
        self.perm = torch.as_tensor(self.order, device=device)
        self.back = torch.as_tensor(np.argsort(self.order, kind="stable"), device=device)   # position of neuron i
        edges = np.cumsum([0] + [len(b) for b in blocks])
        self.spans = list(zip(edges[:-1].tolist(), edges[1:].tolist()))

    def neurons(self, t: torch.Tensor, dim: int = -1) -> torch.Tensor:
        """``t`` with its hidden-neuron axis ``dim`` in block order."""
        return t if self.single else t.index_select(dim, self.perm)

    def restore(self, t: torch.Tensor, dim: int = -1) -> torch.Tensor:
        """``t`` (block order along ``dim``) back in the XyloSpec's neuron order."""
        return t if self.single else t.index_select(dim, self.back)

    def delivery(self, w_in: torch.Tensor, w_rec: torch.Tensor):
        """``(isyn, inputs, events) -> isyn`` in block order, ``w_in`` (Nin, N, S) and ``w_rec`` (N, N, S) given in
        block order."""
        if self.single:
            w = torch.cat([w_in, w_rec], 0)
            w_neg = w.detach().clamp(max=0.0)
            return lambda isyn, x, ev: deliver(isyn, torch.cat([x, ev], 1), w, w_negative=w_neg)
        weights = [torch.cat([w_in[:, a:b], w_rec[a:b, a:b]], 0) for a, b in self.spans]
        negatives = [w.detach().clamp(max=0.0) for w in weights]

        def one_by_one(isyn, x, ev):
            return torch.cat([deliver(isyn[:, a:b], torch.cat([x, ev[:, a:b]], 1), w, w_negative=neg)
                              for (a, b), w, neg in zip(self.spans, weights, negatives)], 1)

        sizes = {b - a for a, b in self.spans}
        if len(sizes) > 1:
            return one_by_one
        # blocks of one size (replicas): every block's sums in one batched product
        k, m, n_in, syn = len(self.spans), sizes.pop(), w_in.shape[0], w_in.shape[2]
        stacked = torch.stack(weights).reshape(k, n_in + m, m * syn)
        stacked_negative = torch.stack(negatives).reshape(k, n_in + m, m * syn)

        def batched(isyn, x, ev):
            b = x.shape[0]
            counts = torch.cat([x.unsqueeze(0).expand(k, b, n_in), ev.reshape(b, k, m).transpose(0, 1)], 2)
            added = torch.bmm(counts, stacked).reshape(k, b, m, syn).transpose(0, 1).reshape(b, k * m, syn)
            with torch.no_grad():
                negative = (torch.bmm(counts, stacked_negative).reshape(k, b, m, syn).transpose(0, 1)
                            .reshape(b, k * m, syn))
            if _in_range(isyn, added, negative):
                return isyn + added
            return one_by_one(isyn, x, ev)

        return batched


class DifferentiableXylo(torch.nn.Module):
    """A ``XyloSpec`` as a trainable model (module doc). ``hidden``: IR population name -> the hidden neurons
    (indices into the XyloSpec's N) that carry it, in the population's neuron order (or (copies, n) for a
    replicated population: its spikes and voltages read as the copies' mean); ``output``: the name of the
    population Xylo's output neurons carry (the last of ``populations``); ``steps``: time steps per sample;
    ``dtype``: default ``compute_dtype(device)``; ``by_blocks``: run the recurrent blocks one at a time
    (``_Blocks``; the same values), for a student whose synapse layout is kept: a weight between two blocks is
    zero and gets no gradient there, as the layout would discard it."""

    def __init__(self, spec: XyloSpec, steps: int, hidden: dict[str, Any] | None = None, output: str = "output", *,
                 learn=("weights", "thresholds", "biases"), slope: float = 5.0, unit=None, unit_out=None,
                 device=None, dtype: torch.dtype | None = None, by_blocks: bool = False):
        super().__init__()
        if any(spec.aliases[k] for k in range(spec.n_hidden)):
            raise SnnccError("fine-tuning a Xylo network with aliases is not supported", field="aliases")
        if int(np.min(spec.threshold)) < 1 or int(np.min(spec.threshold_out)) < 1:
            raise SnnccError("fine-tuning needs thresholds >= 1 (the chip's loop wraps otherwise)", field="threshold")
        self.spec, self.steps, self.slope = spec, int(steps), float(slope)
        self.hidden = {name: np.asarray(idx, np.int64) for name, idx in (hidden or {}).items()}
        self.populations = tuple(self.hidden) + (output,)
        as_t = dict(dtype=dtype or compute_dtype(device), device=device)
        self.by_blocks = bool(by_blocks)
        self._as_t = as_t

        def param(a, kind):
            p = torch.nn.Parameter(torch.as_tensor(np.asarray(a, np.float64), **as_t), requires_grad=kind in learn)
            return p

        self.w_in = param(spec.weights_in, "weights")
        self.w_rec = param(spec.weights_rec, "weights")
        self.w_out = param(spec.weights_out, "weights")
        self.theta = param(spec.threshold, "thresholds")
        self.theta_out = param(spec.threshold_out, "thresholds")
        self.bias = param(spec.bias, "biases")
        self.bias_out = param(spec.bias_out, "biases")
        def fixed(a):
            return torch.as_tensor(np.array(a, np.float64), **as_t)

        self.register_buffer("dash_syn", fixed(np.stack([spec.dash_syn, spec.dash_syn_2], 1)))
        self.register_buffer("dash_mem", fixed(spec.dash_mem))
        self.register_buffer("dash_syn_out", fixed(spec.dash_syn_out)[:, None])
        self.register_buffer("dash_mem_out", fixed(spec.dash_mem_out))
        # the surrogate's scale per neuron (``_Events``): chip units of one IR threshold; None: the threshold
        self.register_buffer("unit", None if unit is None else fixed(unit))
        self.register_buffer("unit_out", None if unit_out is None else fixed(unit_out))
        self._kinds = {"weights": [self.w_in, self.w_rec, self.w_out], "thresholds": [self.theta, self.theta_out],
                       "biases": [self.bias, self.bias_out]}

    # -- the registers the shadows round to ---------------------------------------------------------------
    @staticmethod
    def _int8(w: torch.Tensor) -> torch.Tensor:
        return round_ste(w).clamp(float(CORE.weight_min), float(CORE.weight_max))

    def _weights(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """w_eff = wrap16(w << shift), shaped (Nin, N_ien, 2), (N, N, 2), (N_oen, Nout)."""
        s = self.spec

        def both(w):
            w = w if w.dim() == 3 else w[:, :, None]
            pad = w.new_zeros(w.shape[:2] + (CORE.hidden_synapse_states - w.shape[2],))
            return torch.cat([w, pad], 2)

        return (wrap_ste(both(self._int8(self.w_in)) * 2.0 ** s.weight_shift_in, BITS),
                wrap_ste(both(self._int8(self.w_rec)) * 2.0 ** s.weight_shift_rec, BITS),
                wrap_ste(self._int8(self.w_out) * 2.0 ** s.weight_shift_out, BITS))

    def _theta(self, t: torch.Tensor) -> torch.Tensor:
        return round_ste(t).clamp(1.0, float(CORE.threshold_max))

    def _bias(self, b: torch.Tensor) -> torch.Tensor:
        return round_ste(b).clamp(float(CORE.bias_min), float(CORE.bias_max))

    # -- the chip's step ----------------------------------------------------------------------------------
    def forward(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None, *, record: bool = False):
        """``x`` (B, T, Nin) event counts (clipped to 15 as the chip does); ``force``: population -> (B, T, n)
        events that the synapses leaving those hidden neurons deliver instead of their own."""
        s = self.spec
        x = torch.as_tensor(x, **self._as_t).clamp(max=float(CORE.max_input_spikes))
        b, t_steps, _ = x.shape
        n, n_out, n_ien, n_oen = s.n_hidden, s.n_out, s.n_ien, s.n_oen
        w_in, w_rec, w_out = self._weights()
        theta, theta_out = self._theta(self.theta), self._theta(self.theta_out)
        bias, bias_out = self._bias(self.bias), self._bias(self.bias_out)
        cap_h, cap_o = CORE.max_hidden_spikes, CORE.max_output_spikes
        zeros = dict(dtype=x.dtype, device=x.device)
        isyn = torch.zeros((b, n, CORE.hidden_synapse_states), **zeros)
        v = torch.zeros((b, n), **zeros)
        isyn_o = torch.zeros((b, n_out, 1), **zeros)
        v_o = torch.zeros((b, n_out), **zeros)
        ev = torch.zeros((b, n), **zeros)
        # the hidden neurons run in block order (``_Blocks``); what leaves forward is in the XyloSpec's order
        order = _Blocks(recurrent_blocks(w_rec) if self.by_blocks else [np.arange(n)], x.device)
        forced = [(order.back[torch.as_tensor(self.hidden[p], device=x.device)], torch.as_tensor(f, **zeros))
                  for p, f in (force or {}).items() if p in self.hidden]
        w_in_full = torch.cat([w_in, w_in.new_zeros((w_in.shape[0], n - n_ien, w_in.shape[2]))], 1)
        to_hidden = order.delivery(order.neurons(w_in_full, 1), order.neurons(order.neurons(w_rec, 1), 0))
        # the output synapses read every hidden event in block order (zero rows for the neurons that reach no
        # output neuron) and, where a sum leaves int16, replay them in the chip's order
        oen = order.back[n - n_oen:].tolist()
        w_output = w_out.new_zeros((n, n_out)).index_copy(0, order.back[n - n_oen:], w_out)[:, :, None]
        w_output_negative = w_output.detach().clamp(max=0.0)
        dash_syn, dash_mem = order.neurons(self.dash_syn, 0), order.neurons(self.dash_mem)
        theta, bias = order.neurons(theta), order.neurons(bias)
        u = theta.detach() if self.unit is None else order.neurons(self.unit)
        hid, volt, outs, rec = [], [], [], []
        for t in range(t_steps):
            isyn = to_hidden(isyn, x[:, t], ev)
            isyn_o = deliver(isyn_o, ev, w_output, oen, w_output_negative)
            isyn = isyn - shift_decay(isyn, dash_syn)
            dv = sat16(wrap_ste(-shift_decay(v, dash_mem), BITS) + isyn.sum(-1))
            v = sat16(v + sat16(dv + bias))
            volt.append((v - theta + u) / u)                 # V in IR thresholds (an offset threshold removed)
            ev = events(v, theta, cap_h, self.slope, u)
            v = v - ev * theta
            hid.append(ev)
            if forced:
                ev = ev.clone()
                for idx, f in forced:
                    ev[:, idx] = f[:, t, None] if idx.dim() == 2 else f[:, t]     # every replica forced alike
            isyn_o = isyn_o - shift_decay(isyn_o, self.dash_syn_out)
            dv_o = sat16(wrap_ste(-shift_decay(v_o, self.dash_mem_out), BITS) + isyn_o.sum(-1))
            v_o = sat16(v_o + sat16(dv_o + bias_out))
            o = events(v_o, theta_out, cap_o, self.slope, self.unit_out)
            v_o = v_o - o * theta_out
            outs.append(o)
            if record:
                rec.append((order.restore(v.detach()).clone(), order.restore(isyn.detach(), 1).clone(),
                            v_o.detach().clone(), isyn_o.detach().clone()))
        out = torch.stack(outs, 1)
        spikes = order.restore(torch.stack(hid, 1))
        voltage = order.restore(torch.stack(volt, 1))
        run = StudentRun(counts=out.sum(1), spikes={p: _population(spikes, i) for p, i in self.hidden.items()},
                         voltage={p: _population(voltage, i) for p, i in self.hidden.items()})
        run.spikes[self.populations[-1]] = out
        if record:
            run.states = {"vmem": torch.stack([r[0] for r in rec], 1), "isyn": torch.stack([r[1][..., 0] for r in rec], 1),
                          "isyn2": torch.stack([r[1][..., 1] for r in rec], 1), "spikes": spikes,
                          "vmem_out": torch.stack([r[2] for r in rec], 1),
                          "isyn_out": torch.stack([r[3][..., 0] for r in rec], 1), "output_spikes": out}
        return run

    # -- what the engine needs ----------------------------------------------------------------------------
    def param_groups(self) -> dict[str, list[torch.nn.Parameter]]:
        return {k: [p for p in ps if p.requires_grad] for k, ps in self._kinds.items()}

    @torch.no_grad()
    def project(self) -> None:
        """Keep the shadows within half a step of the registers' ranges."""
        for w in self._kinds["weights"]:
            w.clamp_(CORE.weight_min - 0.49, CORE.weight_max + 0.49)
        for t in self._kinds["thresholds"]:
            t.clamp_(0.51, CORE.threshold_max + 0.49)
        for b in self._kinds["biases"]:
            b.clamp_(CORE.bias_min - 0.49, CORE.bias_max + 0.49)

    @torch.no_grad()
    def export(self) -> XyloSpec:
        """The ``XyloSpec`` with the rounded registers (decays, shifts, aliases and dt unchanged)."""
        s = self.spec

        def ints(p, like):
            return np.rint(p.detach().cpu().numpy()).astype(np.asarray(like).dtype)

        return dataclasses.replace(
            s, weights_in=ints(self._int8(self.w_in), s.weights_in), weights_rec=ints(self._int8(self.w_rec), s.weights_rec),
            weights_out=ints(self._int8(self.w_out), s.weights_out), threshold=ints(self._theta(self.theta), s.threshold),
            threshold_out=ints(self._theta(self.theta_out), s.threshold_out), bias=ints(self._bias(self.bias), s.bias),
            bias_out=ints(self._bias(self.bias_out), s.bias_out))


def _population(x: torch.Tensor, idx: np.ndarray) -> torch.Tensor:
    """A population's neurons of (B, T, N): ``idx`` (n,), or (copies, n) for a replicated population, whose
    copies are averaged (what the readout sees of them)."""
    sel = x[:, :, torch.as_tensor(idx, device=x.device)]
    return sel.mean(2) if np.ndim(idx) == 2 else sel
