"""Loihi's quantization rules in torch, with straight-through rounding (the ``arithmetic`` capability).

The rules (``docs/nir.md``; the Loihi pass ``lowering/quantize.py`` states them for the bundle), for the
whole network at once::

    w_scale = floor(256 / max_k max|W_k|)
    w_q     = clip(round(W * w_scale / 2) * 2, -256, 254)      round half to even (torch.round)
    vThMant = round(theta * w_scale)
    iDecay  = int(4096 * (1 - exp(-dt / tau_syn)));  vDecay likewise with tau_mem

The integer rules (w_scale, vThMant, decay registers) are the Loihi pass's own; only the rounding of
the weights is restated here, in torch, so that it can sit in the autograd graph. In the float
model's units the chip runs ``W' = w_q / w_scale``, threshold ``vThMant / w_scale`` and per-step
decays ``(4096 - iDecay) / 4096``, ``(4096 - vDecay) / 4096``: exactly the chip's arithmetic except
that the chip truncates the decayed current and voltage to integers every step. The backward pass
treats the rounding as the identity (straight-through): ``W' = W + (w_q / w_scale - W).detach()``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass

import torch

from snncc.targets.base import NeuronConstants
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


def loihi_quantization(weights: Mapping[str, torch.Tensor], neurons: NeuronConstants) -> LoihiQuantization:
    """The global-scale quantization record of a network's current ``weights`` and LIF constants."""
    values = list(weights.values())
    max_abs = max(float(w.detach().abs().max()) for w in values)
    ws = weight_scale(max_abs)
    clipped = sum(int((torch.round(w.detach() * ws / 2) * 2 > WEIGHT_RANGE[1]).sum()) for w in values)
    return LoihiQuantization(ws, threshold_mantissa(neurons.threshold, ws), decay_register(neurons.dt, neurons.tau_syn),
                             decay_register(neurons.dt, neurons.tau_mem), clipped)


@dataclass
class QuantizedOnLoihi:
    """``Arithmetic.quantize``'s result: the chip's parameters in float units (weights straight-through)."""

    weights: dict[str, torch.Tensor]
    threshold: float
    alpha: float
    beta: float
    quantization: LoihiQuantization

    @property
    def record(self) -> dict[str, int | float]:
        return asdict(self.quantization)


class LoihiArithmetic:
    """Loihi 1's arithmetic for training: the paper's global-scale rule, straight-through."""

    label = "Loihi"

    def quantize(self, weights: Mapping[str, torch.Tensor], neurons: NeuronConstants) -> QuantizedOnLoihi:
        q = loihi_quantization(weights, neurons)
        return QuantizedOnLoihi({name: fake_quantize(w, q.w_scale) for name, w in weights.items()},
                                q.threshold, q.alpha, q.beta, q)
