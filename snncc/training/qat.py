"""Quantization-aware fine-tuning over Loihi's quantization rules (straight-through estimator).

The rules (spec loihi.md, section 1), for the whole network at once::

    w_scale = floor(256 / max_k max|W_k|)
    w_q     = clip(round(W * w_scale / 2) * 2, -256, 254)      round half to even (torch.round)
    vThMant = round(theta * w_scale)
    iDecay  = int(4096 * (1 - exp(-dt / tau_syn)));  vDecay likewise with tau_mem

The integer rules (w_scale, vThMant, decay registers) are the Loihi pass's own
(``snncc.targets.loihi.lowering.quantize``); only the rounding of the weights is restated here, in torch, so that
it can sit in the autograd graph. The fake-quantized forward pass runs the float model with ``W' = w_q / w_scale``, threshold
``vThMant / w_scale`` and decays ``(4096 - iDecay) / 4096``, ``(4096 - vDecay) / 4096``: exactly
the chip's arithmetic in float units, except that the chip truncates the decayed current and
voltage to integers every step. The backward pass treats the rounding as the identity
(straight-through): ``W' = W + (w_q / w_scale - W).detach()``.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass, replace

import torch
from torch import nn
from torch.func import functional_call

from snncc.errors import SnnccError
from snncc.models import SpikingClassifier
from snncc.targets.loihi.chip import DECAY_ONE, WEIGHT_MAX, WEIGHT_MIN
from snncc.targets.loihi.lowering.quantize import decay_register, threshold_mantissa, weight_scale

WEIGHT_RANGE = (WEIGHT_MIN, WEIGHT_MAX)


@dataclass
class LoihiQuantization:
    """What the chip would be given for a network (the global-scale rule of the paper)."""

    w_scale: int
    v_th_mant: int
    i_decay: int
    v_decay: int
    clipped_weights: int      # weights that rounded to +256 and were clipped to 254

    @property
    def threshold(self) -> float:
        return self.v_th_mant / self.w_scale

    @property
    def alpha(self) -> float:
        return (DECAY_ONE - self.i_decay) / DECAY_ONE

    @property
    def beta(self) -> float:
        return (DECAY_ONE - self.v_decay) / DECAY_ONE


def quantize_weights(w: torch.Tensor, w_scale: int) -> torch.Tensor:
    """Integer-valued (float dtype) clip(round(W * w_scale / 2) * 2, -256, 254), round half to even."""
    return torch.clamp(torch.round(w * w_scale / 2) * 2, *WEIGHT_RANGE)


def fake_quantize(w: torch.Tensor, w_scale: int) -> torch.Tensor:
    """w_q / w_scale in the forward pass, identity gradient in the backward pass."""
    return w + (quantize_weights(w.detach(), w_scale) / w_scale - w).detach()


def spiking_weights(model: SpikingClassifier) -> dict[str, torch.Tensor]:
    return {name: p for name, p in model.named_parameters()}


def loihi_quantization(model: SpikingClassifier) -> LoihiQuantization:
    """The global-scale quantization record of ``model``'s current weights."""
    if not isinstance(model, SpikingClassifier):
        raise SnnccError("quantization-aware fine-tuning applies to spiking models (rsnn, ffsnn) only", field="model")
    weights = list(spiking_weights(model).values())
    max_abs = max(float(w.detach().abs().max()) for w in weights)
    ws = weight_scale(max_abs)
    clipped = sum(int((torch.round(w.detach() * ws / 2) * 2 > WEIGHT_RANGE[1]).sum()) for w in weights)
    cfg = model.config
    return LoihiQuantization(ws, threshold_mantissa(cfg.threshold, ws), decay_register(cfg.dt, cfg.tau_syn),
                             decay_register(cfg.dt, cfg.tau_mem), clipped)


def _tau_for(decay: float, dt: float) -> float:
    """The time constant whose exp(-dt/tau) equals ``decay``."""
    if decay >= 1.0:
        return math.inf
    if decay <= 0.0:
        return 1e-300
    return -dt / math.log(decay)


@contextmanager
def chip_config(model: SpikingClassifier, q: LoihiQuantization, quantize_decays: bool = True):
    """Temporarily give ``model`` the chip's threshold (and decays)."""
    saved = model.config
    cfg = replace(saved, threshold=q.threshold)
    if quantize_decays:
        cfg = replace(cfg, tau_syn=_tau_for(q.alpha, saved.dt), tau_mem=_tau_for(q.beta, saved.dt))
    model.config = cfg
    try:
        yield model
    finally:
        model.config = saved


def quantized_forward(model: nn.Module, x: torch.Tensor, quantize_decays: bool = True):
    """The model's forward pass with Loihi-quantized weights, threshold and decays (STE gradients)."""
    q = loihi_quantization(model)
    params = {name: fake_quantize(p, q.w_scale) for name, p in spiking_weights(model).items()}
    with chip_config(model, q, quantize_decays):
        return functional_call(model, params, (x,))
