"""The C target's integer arithmetic as a trainable torch model (``kit.finetuning.DifferentiableArithmetic``).

Forward: exactly the emulator's arithmetic (``emulation/emulator.py``) in float64, every value an integer below
2**53 (products alpha * I below 2**47, one step's synaptic input below 2**52: checked when the network is
built), so its spikes, currents and voltages equal the emulator's and the C's on the exported integers. What
trains are float shadows that round to the deployed integers (straight-through, ``kit.finetuning``):

    weights      each projection's int8/int16 weights (shadow in weight units; clamped to +-limit)
    thresholds   per neuron, shadow in units of 2**SHADOW_SHIFT state units (so one step of the optimiser moves a
                 threshold by a small fraction of itself), rounded to whole state units, at least 1
    biases       current-bias terms and voltage biases, same units as thresholds

Exponents, decays, refractory periods, resets and the spike rule are kept. Spikes are 0/1 (or counts) forward,
the fast-sigmoid surrogate backward (``kit.finetuning.spike``); the reset uses the forward spikes without a
gradient through them.
"""

from __future__ import annotations

import copy

import numpy as np
import torch

from snncc.targets.kit.finetuning import StudentRun, floor_ste, round_ste, spike
from snncc.targets.c.lowering.network import BiasTerm, CNetwork
from snncc.targets.c.options import DECAY_BITS, THRESHOLD_BITS, WEIGHT_LIMIT

SHADOW_SHIFT = THRESHOLD_BITS - 7          # a threshold near 2**20 units is a shadow near 128..256
INT32_MIN, INT32_MAX = -float(1 << 31), float((1 << 31) - 1)
HALF = float(1 << (DECAY_BITS - 1))
ONE = float(1 << DECAY_BITS)


class DifferentiableC(torch.nn.Module):
    """``net`` as a differentiable model over ``steps`` steps (module doc)."""

    def __init__(self, net: CNetwork, steps: int, *, slope: float = 5.0, device=None):   # noqa: ANN001
        super().__init__()
        self.net = net
        self.steps = int(steps)
        self.slope = float(slope)
        dev = torch.device(device) if device is not None else torch.device("cpu")
        order = [i for i in range(len(net.populations)) if i != net.output] + [net.output]
        self.populations = tuple(net.populations[i].name for i in order)
        f64 = dict(dtype=torch.float64, device=dev)
        self.w = torch.nn.ParameterList(torch.nn.Parameter(torch.as_tensor(q.weights.astype(np.float64), **f64))
                                        for q in net.projections)
        self.scale = [torch.as_tensor(np.exp2(q.exponent.astype(np.float64)), **f64) for q in net.projections]
        self.th = torch.nn.ParameterList(
            torch.nn.Parameter(torch.as_tensor(p.threshold.astype(np.float64) / 2.0 ** SHADOW_SHIFT, **f64))
            for p in net.populations)
        self.bi = torch.nn.ParameterList()
        self.bi_index: list[tuple[int, int, int]] = []           # (population, term, start)
        for i, p in enumerate(net.populations):
            for k, term in enumerate(p.bias_i):
                self.bi_index.append((i, k, int(term.start)))
                self.bi.append(torch.nn.Parameter(torch.as_tensor(term.values / 2.0 ** SHADOW_SHIFT, **f64)))
        self.bv = torch.nn.ParameterList()
        self.bv_index: list[int] = []
        for i, p in enumerate(net.populations):
            if p.bias_v is not None:
                self.bv_index.append(i)
                self.bv.append(torch.nn.Parameter(torch.as_tensor(p.bias_v / 2.0 ** SHADOW_SHIFT, **f64)))
        self.alpha = [torch.as_tensor(p.alpha.astype(np.float64), **f64) for p in net.populations]
        self.beta = [torch.as_tensor(p.beta.astype(np.float64), **f64) for p in net.populations]
        self.device = dev

    # -- the integers the shadows round to ------------------------------------------------------------------
    def _weights(self) -> list[torch.Tensor]:
        return [torch.clamp(round_ste(w), -WEIGHT_LIMIT[q.bits], WEIGHT_LIMIT[q.bits])
                for w, q in zip(self.w, self.net.projections)]

    def _thresholds(self) -> list[torch.Tensor]:
        out = []
        for th, p in zip(self.th, self.net.populations):
            if not p.fires:
                out.append(torch.full_like(th, INT32_MAX))
            else:
                out.append(torch.clamp(round_ste(th * 2.0 ** SHADOW_SHIFT), 1.0, INT32_MAX))
        return out

    @staticmethod
    def _bias(b: torch.Tensor) -> torch.Tensor:
        return torch.clamp(round_ste(b * 2.0 ** SHADOW_SHIFT), INT32_MIN, INT32_MAX)

    # -- the protocol ---------------------------------------------------------------------------------------
    def forward(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None) -> StudentRun:
        net = self.net
        force = force or {}
        x = torch.as_tensor(x, dtype=torch.float64, device=self.device)
        batch, steps = int(x.shape[0]), int(x.shape[1])
        weights, thetas = self._weights(), self._thresholds()
        bias_i: dict[int, list[tuple[int, torch.Tensor]]] = {}
        for (i, _, start), b in zip(self.bi_index, self.bi):
            bias_i.setdefault(i, []).append((start, self._bias(b)))
        bias_v = {i: self._bias(b) for i, b in zip(self.bv_index, self.bv)}
        pops = net.populations
        zeros = [torch.zeros(batch, p.n, dtype=torch.float64, device=self.device) for p in pops]
        cur, vol = list(zeros), list(zeros)
        ref = [torch.zeros(batch, p.n, dtype=torch.float64, device=self.device) for p in pops]
        sent: dict[int, list[torch.Tensor]] = {-1: [], **{i: [] for i in range(len(pops))}}   # what synapses read
        spikes: dict[str, list[torch.Tensor]] = {p.name: [] for p in pops}
        volts: dict[str, list[torch.Tensor]] = {p.name: [] for p in pops}
        for t in range(steps):
            sent[-1].append(x[:, t])
            for i, pop in enumerate(pops):
                syn = zeros[i]
                for k, q in enumerate(net.projections):
                    if q.target != i or t < q.delay:
                        continue
                    syn = syn + (sent[q.source][t - q.delay] @ weights[k]) * self.scale[k]
                i_new = floor_ste((self.alpha[i] * cur[i] + HALF) / ONE) + syn
                for start, b in bias_i.get(i, ()):
                    if t >= start:
                        i_new = i_new + b
                i_new = torch.clamp(i_new, INT32_MIN, INT32_MAX)
                v_new = floor_ste((self.beta[i] * vol[i] + HALF) / ONE) + i_new
                if i in bias_v:
                    v_new = v_new + bias_v[i]
                v_new = torch.clamp(v_new, INT32_MIN, INT32_MAX)
                held = ref[i] > 0
                v_new = torch.where(held, torch.zeros_like(v_new), v_new)
                ref[i] = torch.where(held, ref[i] - 1, ref[i])
                theta = thetas[i]
                volts[pop.name].append(v_new / theta)
                if pop.fires:
                    s = spike(v_new, theta, self.slope, pop.fire_test == ">")
                    if pop.counts:
                        ratio = torch.div(v_new.detach(), theta.detach(), rounding_mode="floor")
                        exact = ratio if pop.fire_test == ">=" else \
                            torch.ceil(v_new.detach() / theta.detach()) - 1.0
                        hard = torch.clamp(exact, 0.0, float(pop.max_spikes))
                        s = hard + (s - s.detach())
                    count = s.detach()
                    fired = count > 0
                    if pop.reset == "zero":
                        v_new = torch.where(fired, torch.zeros_like(v_new), v_new - count * theta)
                    else:
                        v_new = v_new - count * theta
                    if pop.refractory > 1:
                        ref[i] = torch.where(fired, torch.full_like(ref[i], pop.refractory - 1), ref[i])
                else:
                    s = torch.zeros_like(v_new)
                cur[i], vol[i] = i_new, v_new
                spikes[pop.name].append(s)
                sent[i].append(force[pop.name][:, t] if pop.name in force else s)
        out = {k: torch.stack(v, dim=1) for k, v in spikes.items()}
        return StudentRun(counts=out[pops[net.output].name].sum(dim=1), spikes=out,
                          voltage={k: torch.stack(v, dim=1) for k, v in volts.items()})

    def param_groups(self) -> dict[str, list[torch.nn.Parameter]]:
        fires = [th for th, p in zip(self.th, self.net.populations) if p.fires]
        return {"weights": list(self.w), "thresholds": fires, "biases": list(self.bi) + list(self.bv)}

    def project(self) -> None:
        with torch.no_grad():
            for w, q in zip(self.w, self.net.projections):
                w.clamp_(-WEIGHT_LIMIT[q.bits], WEIGHT_LIMIT[q.bits])
            for th in self.th:
                th.clamp_(1.0 / 2.0 ** SHADOW_SHIFT, INT32_MAX / 2.0 ** SHADOW_SHIFT)
            for b in list(self.bi) + list(self.bv):
                b.clamp_(INT32_MIN / 2.0 ** SHADOW_SHIFT, INT32_MAX / 2.0 ** SHADOW_SHIFT)

    def export(self) -> CNetwork:
        """The network with the integers the shadows round to (what the artefact writes)."""
        net = copy.deepcopy(self.net)
        with torch.no_grad():
            for q, w in zip(net.projections, self._weights()):
                q.weights = w.cpu().numpy().astype(np.int16)
            for p, th in zip(net.populations, self._thresholds()):
                if p.fires:
                    p.threshold = th.cpu().numpy().astype(np.int64)
            for (i, k, start), b in zip(self.bi_index, self.bi):
                net.populations[i].bias_i[k] = BiasTerm(start, self._bias(b).cpu().numpy().astype(np.int64))
            for i, b in zip(self.bv_index, self.bv):
                net.populations[i].bias_v = self._bias(b).cpu().numpy().astype(np.int64)
        return net


__all__ = ["DifferentiableC", "SHADOW_SHIFT"]
