"""The paper's spiking classifiers (RSNN and FFSNN): inputs -> CUBA LIF hidden -> CUBA LIF readout.

Both use the IR's integrate-then-fire semantics with an explicit update order:

* ``spytorch`` — the authors' training loop (``mem[t+1] = (beta*mem[t] + syn[t])*(1 - S[t])``)
  which is exactly integrate-then-fire with refractory 2 and edge delays in 2, rec 3, out 2;
* ``loihi`` — plain integrate-then-fire with one-step delays on every edge and no refractory
  period, the cheapest order on hardware.

Weights keep the authors' ``(in, out)`` orientation (``h = x @ W``); the reset is detached from
the gradient; spikes use the fast-sigmoid surrogate with ``scale``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import torch
from torch import nn

from snncc.models.surrogate import spike

UPDATE_ORDERS: dict[str, dict[str, int]] = {
    "spytorch": {"delay_in": 2, "delay_rec": 3, "delay_out": 2, "refractory": 2},
    "loihi": {"delay_in": 1, "delay_rec": 1, "delay_out": 1, "refractory": 1},
}


@dataclass
class SNNConfig:
    """Architecture record of an RSNN/FFSNN (stored in checkpoints as a plain dict)."""

    n_inputs: int = 24          # event channels before input copies
    n_hidden: int = 450
    n_outputs: int = 28         # 27 letters + 1 spare class
    recurrent: bool = True
    input_copies: int = 2
    tau_mem: float = 0.06       # s
    tau_syn: float = 0.006      # s (tau_mem / tau_ratio)
    dt: float = 0.005           # s (time_bin_size)
    threshold: float = 1.0
    scale: float = 5.0          # surrogate steepness
    order: str = "spytorch"

    @property
    def kind(self) -> str:
        return "rsnn" if self.recurrent else "ffsnn"

    @property
    def timing(self) -> dict[str, int]:
        return UPDATE_ORDERS[self.order]


def shift_time(x: torch.Tensor, d: int) -> torch.Tensor:
    """x[:, t - d] along the time axis (zeros for t < d)."""
    if d == 0:
        return x
    return torch.cat([x.new_zeros(x.shape[0], min(d, x.shape[1]), *x.shape[2:]), x[:, : max(x.shape[1] - d, 0)]], dim=1)


def lif_sequence(
    drive: torch.Tensor,
    alpha: float,
    beta: float,
    threshold: float,
    scale: float,
    refractory: int,
    rec_weight: torch.Tensor | None = None,
    rec_delay: int = 1,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Differentiable CUBA LIF over a sequence; returns (spikes, post-reset voltage), each (B, T, n).

    I[t] = alpha*I[t-1] + drive[t] + s[t-rec_delay] @ rec_weight;  V[t] = beta*V[t-1] + I[t];
    V held at 0 while refractory; s[t] = H(V[t] - threshold); V[t] *= (1 - s[t]) (detached).
    """
    batch, steps, n = drive.shape
    i_syn = drive.new_zeros(batch, n)
    v = drive.new_zeros(batch, n)
    ref = torch.zeros(batch, n, dtype=torch.int32, device=drive.device)
    spikes: list[torch.Tensor] = []
    volts: list[torch.Tensor] = []
    drive_steps = drive.unbind(1)  # one view per step; its backward stacks once (drive[:, t] refilled a full zero tensor per step)
    for t in range(steps):
        x = drive_steps[t]
        if rec_weight is not None and t - rec_delay >= 0:
            x = x + spikes[t - rec_delay] @ rec_weight
        i_syn = alpha * i_syn + x
        v = beta * v + i_syn
        if refractory > 1:
            active = (ref == 0).to(v.dtype)
            v = v * active
            ref = torch.clamp(ref - 1, min=0)
        s = spike(v - threshold, scale)
        v = v * (1.0 - s.detach())
        if refractory > 1:
            ref = torch.where(s.detach() > 0, torch.full_like(ref, refractory - 1), ref)
        spikes.append(s)
        volts.append(v)
    return torch.stack(spikes, dim=1), torch.stack(volts, dim=1)


class SpikingClassifier(nn.Module):
    """RSNN (``recurrent=True``) or FFSNN of the paper; ``forward`` takes (B, T, n_inputs) events."""

    def __init__(self, config: SNNConfig | None = None, **overrides):
        super().__init__()
        cfg = config or SNNConfig()
        if overrides:
            cfg = SNNConfig(**{**asdict(cfg), **overrides})
        if cfg.order not in UPDATE_ORDERS:
            raise ValueError(f"order must be one of {sorted(UPDATE_ORDERS)}")
        self.config = cfg
        n_in = cfg.n_inputs * cfg.input_copies
        self.w_in = nn.Parameter(torch.empty(n_in, cfg.n_hidden))
        self.w_out = nn.Parameter(torch.empty(cfg.n_hidden, cfg.n_outputs))
        self.v_rec = nn.Parameter(torch.empty(cfg.n_hidden, cfg.n_hidden)) if cfg.recurrent else None
        self.reset_parameters()

    def reset_parameters(self, fwd_weight_scale: float = 1.0, weight_scale_factor: float = 0.01) -> None:
        """The authors' initialisation: N(0, (fws/sqrt(fan_in))^2), recurrent scaled by wsf."""
        cfg = self.config
        n_in = cfg.n_inputs * cfg.input_copies
        with torch.no_grad():
            self.w_in.normal_(0.0, fwd_weight_scale / math.sqrt(n_in))
            self.w_out.normal_(0.0, fwd_weight_scale / math.sqrt(cfg.n_hidden))
            if self.v_rec is not None:
                self.v_rec.normal_(0.0, weight_scale_factor * fwd_weight_scale / math.sqrt(cfg.n_hidden))

    @property
    def alpha(self) -> float:
        return math.exp(-self.config.dt / self.config.tau_syn)

    @property
    def beta(self) -> float:
        return math.exp(-self.config.dt / self.config.tau_mem)

    def tile_inputs(self, x: torch.Tensor) -> torch.Tensor:
        """The authors' ``inputs.tile((nb_input_copies,))``: copies side by side on the channel axis."""
        if x.shape[-1] == self.config.n_inputs * self.config.input_copies:
            return x
        return x.repeat(1, 1, self.config.input_copies)

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Return (output spikes (B, T, n_out), hidden spikes (B, T, n_hidden))."""
        cfg, timing = self.config, self.config.timing
        x = self.tile_inputs(x.to(self.w_in.dtype))
        drive_h = shift_time(x @ self.w_in, timing["delay_in"])
        s_h, _ = lif_sequence(drive_h, self.alpha, self.beta, cfg.threshold, cfg.scale, timing["refractory"],
                              self.v_rec, timing["delay_rec"])
        drive_o = shift_time(s_h @ self.w_out, timing["delay_out"])
        s_o, _ = lif_sequence(drive_o, self.alpha, self.beta, cfg.threshold, cfg.scale, timing["refractory"])
        return s_o, s_h

    def architecture(self) -> dict:
        return {"kind": self.config.kind, **asdict(self.config)}

    def weight_list(self) -> list[torch.Tensor]:
        """The authors' published layout: [W_in, W_out, V_rec] (RSNN) or [W_in, W_out]."""
        ws = [self.w_in.detach().clone(), self.w_out.detach().clone()]
        if self.v_rec is not None:
            ws.append(self.v_rec.detach().clone())
        return ws
