"""A lowered Xylo network's differentiable arithmetic in the model's own time (the student of ``compile --finetune``).

The Xylo lowering runs population P ``s_P`` steps late on the chip (``lowering/timing.py``): the chip is fed
``input_pad`` zero steps before a sample's T steps (and zeros after, to ``T + output_lag`` steps in all), and
its output step ``t + output_lag`` is the model's step t. ``ChipTimeStudent`` wraps ``DifferentiableXylo``
(built over the chip's steps) so that it takes and returns the model's time, as the engine expects
(``snncc.finetune.protocol``):

    x_chip       = [0] * input_pad ++ x ++ [0] * max(0, output_lag - input_pad)
    counts       = sum over t < T of output_chip[t + output_lag]
    spikes[P][t] = hidden_chip[t + s_P][neurons of P]           (the same for V / theta)
    force[P]     = the teacher's spikes of P placed at chip steps s_P .. s_P + T - 1

What training may change is limited to what the lowering's design rules already accepted: a weight that
the lowering left at zero stays zero (the synapse layout, fan-out and expansion limits are kept), and the
neurons that carry no population (the always-on bias source, relays, the readout's copies) keep their
threshold, bias and incoming weights, so they still do what the lowering built them for; output neurons that
copy a hidden readout keep every register. ``project`` enforces both after every optimiser step.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from snncc.targets.xylo.finetune.arithmetic import DifferentiableXylo
from snncc.targets.xylo.spec import XyloSpec


def chip_steps(steps: int, input_pad: int, output_lag: int) -> int:
    """Chip steps that hold a sample of ``steps`` model steps (``feed.chip_window``)."""
    return int(input_pad) + int(steps) + max(0, int(output_lag) - int(input_pad))


class ChipTimeStudent(torch.nn.Module):
    """``DifferentiableXylo`` over ``spec`` seen in the model's time (module doc). ``hidden``: population ->
    hidden neuron indices; ``output``: the readout population; ``shifts``: population -> steps late on the chip."""

    def __init__(self, spec: XyloSpec, steps: int, hidden: dict[str, Any], output: str, *, input_pad: int,
                 output_lag: int, shifts: dict[str, int], learn=("weights", "thresholds", "biases"),
                 slope: float = 5.0, unit=None, unit_out=None, also_learned=(), fixed_output: bool = False,
                 device=None):
        super().__init__()
        self.steps = int(steps)
        self.input_pad, self.output_lag = int(input_pad), int(output_lag)
        self.shifts = {p: int(shifts[p]) for p in hidden}
        self.core = DifferentiableXylo(spec, chip_steps(steps, input_pad, output_lag), hidden, output, learn=learn,
                                       slope=slope, unit=unit, unit_out=unit_out, device=device,
                                       by_blocks=True)          # the layout is kept (``project``)
        self.populations = self.core.populations
        carried = np.zeros(spec.n_hidden, bool)
        for idx in hidden.values():
            carried[np.asarray(idx, np.int64)] = True
        carried[np.asarray(also_learned, np.int64)] = True
        as_t = dict(dtype=self.core.dash_mem.dtype, device=device)
        # neurons that carry no population keep what reaches them too (a relay's gain, a copy's cancellation)
        self.register_buffer("_fixed_w_in", torch.as_tensor(np.asarray(spec.weights_in, np.float64)[:, ~carried], **as_t))
        self.register_buffer("_fixed_w_rec", torch.as_tensor(np.asarray(spec.weights_rec, np.float64)[:, ~carried], **as_t))
        self.fixed_output = bool(fixed_output)
        if self.fixed_output:         # output neurons that copy a hidden readout: every register of theirs is kept
            self.register_buffer("_fixed_w_out", torch.as_tensor(np.asarray(spec.weights_out, np.float64), **as_t))
            self.register_buffer("_fixed_theta_out", torch.as_tensor(np.asarray(spec.threshold_out, np.float64), **as_t))
            self.register_buffer("_fixed_bias_out", torch.as_tensor(np.asarray(spec.bias_out, np.float64), **as_t))
        self.register_buffer("_keep_w_in", torch.as_tensor(np.asarray(spec.weights_in) != 0, **as_t))
        self.register_buffer("_keep_w_rec", torch.as_tensor(np.asarray(spec.weights_rec) != 0, **as_t))
        self.register_buffer("_keep_w_out", torch.as_tensor(np.asarray(spec.weights_out) != 0, **as_t))
        self._fixed = torch.as_tensor(np.flatnonzero(~carried), device=device)
        self.register_buffer("_fixed_theta", torch.as_tensor(np.asarray(spec.threshold, np.float64)[~carried], **as_t))
        self.register_buffer("_fixed_bias", torch.as_tensor(np.asarray(spec.bias, np.float64)[~carried], **as_t))

    def chip_input(self, x: torch.Tensor) -> torch.Tensor:
        b, t, c = x.shape
        tail = max(0, self.output_lag - self.input_pad)
        return torch.cat([x.new_zeros((b, self.input_pad, c)), x, x.new_zeros((b, tail, c))], 1)

    def _in_chip_time(self, f: torch.Tensor, shift: int) -> torch.Tensor:
        b, t, n = f.shape
        total = chip_steps(self.steps, self.input_pad, self.output_lag)
        return torch.cat([f.new_zeros((b, shift, n)), f, f.new_zeros((b, max(0, total - shift - t), n))], 1)[:, :total]

    def forward(self, x: torch.Tensor, force: dict[str, torch.Tensor] | None = None):
        x = torch.as_tensor(x, dtype=self.core.dash_mem.dtype, device=self.core.dash_mem.device)
        chip_force = None
        if force:
            chip_force = {p: self._in_chip_time(torch.as_tensor(f, dtype=x.dtype, device=x.device),
                                                self.shifts[p]) for p, f in force.items() if p in self.shifts}
        run = self.core(self.chip_input(x), chip_force)
        out_name = self.populations[-1]
        t = x.shape[1]
        out = run.spikes[out_name][:, self.output_lag:self.output_lag + t]
        run.counts = out.sum(1)
        for p, s in self.shifts.items():
            run.spikes[p] = run.spikes[p][:, s:s + t]
            run.voltage[p] = run.voltage[p][:, s:s + t]
        run.spikes[out_name] = out
        return run

    def param_groups(self) -> dict[str, list[torch.nn.Parameter]]:
        return self.core.param_groups()

    @torch.no_grad()
    def project(self) -> None:
        """The core's range clamps, then the layout and the fixed neurons restored (module doc)."""
        self.core.project()
        c = self.core
        c.w_in.mul_(self._keep_w_in)
        c.w_rec.mul_(self._keep_w_rec)
        c.w_out.mul_(self._keep_w_out)
        if self._fixed.numel():
            c.theta[self._fixed] = self._fixed_theta
            c.bias[self._fixed] = self._fixed_bias
            c.w_in[:, self._fixed] = self._fixed_w_in
            c.w_rec[:, self._fixed] = self._fixed_w_rec
        if self.fixed_output:
            c.w_out.copy_(self._fixed_w_out)
            c.theta_out.copy_(self._fixed_theta_out)
            c.bias_out.copy_(self._fixed_bias_out)

    @torch.no_grad()
    def export(self) -> XyloSpec:
        return self.core.export()
