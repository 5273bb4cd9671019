"""Quantization-aware fine-tuning through a target's arithmetic (straight-through estimator).

The target states its arithmetic (capability ``arithmetic``, ``snncc.targets.base.Arithmetic``):
given the network's weights and LIF constants it returns the parameters the chip would run, in the
float model's units -- weights whose forward value is the chip's and whose gradient is the identity,
the chip's threshold and per-step decay factors. The fake-quantized forward pass runs the float
model with those parameters (``quantized_forward``); training it moves the float weights so that
the chip's parameters classify well. Loihi's rules: ``snncc.targets.loihi.arithmetic``.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from typing import TYPE_CHECKING

import torch
from torch import nn
from torch.func import functional_call

from snncc.errors import SnnccError
from snncc.models import SpikingClassifier
from snncc.targets import DEFAULT_TARGET

if TYPE_CHECKING:
    from snncc.targets.base import Arithmetic, QuantizedParameters



def target_arithmetic(target: str = DEFAULT_TARGET) -> Arithmetic:
    """The arithmetic of the registered target ``target`` (refused in one line when it has none)."""
    from snncc.targets import capability, get_target

    return capability(get_target(target), "arithmetic",
                      rule=f"target {target!r} offers no differentiable arithmetic to fine-tune through")()


def spiking_weights(model: SpikingClassifier) -> dict[str, torch.Tensor]:
    return {name: p for name, p in model.named_parameters()}


def chip_parameters(model: SpikingClassifier, arithmetic: Arithmetic) -> QuantizedParameters:
    """The chip's parameters for ``model``'s current weights and constants (straight-through weights)."""
    from snncc.targets.base import NeuronConstants

    if not isinstance(model, SpikingClassifier):
        raise SnnccError("quantization-aware fine-tuning applies to spiking models (rsnn, ffsnn) only", field="model")
    cfg = model.config
    return arithmetic.quantize(spiking_weights(model), NeuronConstants(cfg.threshold, cfg.dt, cfg.tau_syn, cfg.tau_mem))


def _tau_for(decay: float, dt: float) -> float:
    """The time constant whose exp(-dt/tau) equals ``decay``."""
    if decay >= 1.0:
        return math.inf
    if decay <= 0.0:
        return 1e-300
    return -dt / math.log(decay)


@contextmanager
def chip_config(model: SpikingClassifier, q: QuantizedParameters, quantize_decays: bool = True):
    """Temporarily give ``model`` the chip's threshold (and decays)."""
    from dataclasses import replace

    saved = model.config
    cfg = replace(saved, threshold=q.threshold)
    if quantize_decays:
        cfg = replace(cfg, tau_syn=_tau_for(q.alpha, saved.dt), tau_mem=_tau_for(q.beta, saved.dt))
    model.config = cfg
    try:
        yield model
    finally:
        model.config = saved


def quantized_forward(model: nn.Module, x: torch.Tensor, arithmetic: Arithmetic | None = None,
                      quantize_decays: bool = True):
    """The model's forward pass with the chip's weights, threshold and decays (STE gradients);
    ``arithmetic`` default: Loihi's."""
    q = chip_parameters(model, arithmetic or target_arithmetic())
    with chip_config(model, q, quantize_decays):
        return functional_call(model, dict(q.weights), (x,))
