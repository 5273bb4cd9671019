"""The fast-sigmoid surrogate gradient of the paper's SpyTorch code.

forward: S = H(x) = 1[x > 0];  backward: dS/dx ~ 1 / (scale*|x| + 1)^2
"""

from __future__ import annotations

import torch


class FastSigmoidSpike(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x: torch.Tensor, scale: float) -> torch.Tensor:
        ctx.save_for_backward(x)
        ctx.scale = scale
        return (x > 0).to(x.dtype)

    @staticmethod
    def backward(ctx, grad: torch.Tensor):
        (x,) = ctx.saved_tensors
        return grad / (ctx.scale * x.abs() + 1.0) ** 2, None


def spike(x: torch.Tensor, scale: float) -> torch.Tensor:
    """Heaviside step with the fast-sigmoid surrogate gradient."""
    return FastSigmoidSpike.apply(x, scale)
