"""Straight-through operators for differentiable models of integer chip arithmetic.

Each forward pass computes the integer operation EXACTLY (float64 tensors holding integers below
2**53 add, multiply by small integers and divide by powers of two without error); the backward
pass replaces the step function by a smooth stand-in:

    round_ste(x), trunc_ste(x), floor_ste(x)   forward: torch.round (half to even) / trunc / floor;
                                               backward: identity
    wrap_ste(x, bits)                          forward: two's complement wrap into ``bits`` + sign;
                                               backward: identity
    spike(v, theta, slope, strict)             forward: v > theta (v >= theta when not strict), as 0/1;
                                               backward: the fast-sigmoid surrogate
                                               h(z) = 1 / (1 + slope * |z|)**2,  z = (v - theta) / |theta|
                                               dS/dv = h / |theta|,  dS/dtheta = -h / |theta|

``x + (f(x) - x).detach()`` is not used: in floating point it need not equal f(x) exactly.
"""

from __future__ import annotations

import torch


class _RoundSTE(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        return torch.round(x)

    @staticmethod
    def backward(ctx, g):
        return g


class _TruncSTE(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        return torch.trunc(x)

    @staticmethod
    def backward(ctx, g):
        return g


class _FloorSTE(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x):
        return torch.floor(x)

    @staticmethod
    def backward(ctx, g):
        return g


class _WrapSTE(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, bits: int):
        half = float(1 << bits)
        span = 2.0 * half
        return x - span * torch.floor((x + half) / span)

    @staticmethod
    def backward(ctx, g):
        return g, None


class _Spike(torch.autograd.Function):
    @staticmethod
    def forward(ctx, v, theta, slope: float, strict: bool):
        ctx.save_for_backward(v, theta)
        ctx.slope = slope
        return (v > theta if strict else v >= theta).to(v.dtype)

    @staticmethod
    def backward(ctx, g):
        v, theta = ctx.saved_tensors
        scale = theta.abs().clamp_min(1e-12)
        h = 1.0 / (1.0 + ctx.slope * ((v - theta) / scale).abs()) ** 2 / scale
        gv = g * h
        gt = None
        if ctx.needs_input_grad[1]:
            gt = -gv
            gt = gt.sum_to_size(theta.shape) if theta.dim() else gt.sum()
        return gv, gt, None, None


def round_ste(x: torch.Tensor) -> torch.Tensor:
    return _RoundSTE.apply(x)


def trunc_ste(x: torch.Tensor) -> torch.Tensor:
    return _TruncSTE.apply(x)


def floor_ste(x: torch.Tensor) -> torch.Tensor:
    return _FloorSTE.apply(x)


def wrap_ste(x: torch.Tensor, bits: int) -> torch.Tensor:
    return _WrapSTE.apply(x, int(bits))


def spike(v: torch.Tensor, theta: torch.Tensor, slope: float = 5.0, strict: bool = True) -> torch.Tensor:
    """0/1 spikes ``v > theta`` (``>=`` when not ``strict``) with a surrogate gradient; ``theta`` broadcasts."""
    return _Spike.apply(v, theta, float(slope), bool(strict))
