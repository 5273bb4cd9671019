"""One Loihi layer's time loop as a single autograd function with hand-written backpropagation
through time (the same straight-through gradients as the step-by-step graph of
``differentiable.py``, without building thousands of autograd nodes per sample).

Forward, per chip step t (exact integers in float64, as ``emulation/emulator.py``):

    q   = D[t] + sum_d R_d r[t-1-d]                r: the spikes the recurrent synapses read
    u   = wrap23( trunc(u * ku / 4096) + wrap21(q) )
    v1  = trunc(v * kv / 4096) + u + b ;  v2 = clip(v1, vmin, vmax) ;  v3 = 0 if refractory else v2
    s   = v3 > theta ;  v = v3 * (1 - s) ;  refractory counter as on the chip

Backward (adjoints gu, gv of the state after step t, flowing from t + 1):

    g_v3 = gv (1 - s) + g_Vpre[t] + h * g_s ,   g_s = g_S[t] + g_rec[t] - gv v3  (reset not detached)
    g_theta -= h g_s ;   g_v1 = g_v3 [not refractory] [vmin <= v1 <= vmax]
    g_b += g_v1 ;  g_kv += g_v1 v_prev / 4096 ;  gv <- g_v1 kv / 4096
    g_u = gu + g_v1 ;  g_ku += g_u u_prev / 4096 ;  gu <- g_u ku / 4096 ;  g_D[t] = g_q = g_u
    g_R_d += g_q^T r[t-1-d] ;  g_rec[t-1-d] += g_q R_d     (not when r is forced)

with the surrogate h = 1 / (1 + slope |v3 - theta| / |theta|)**2 / |theta| (``snncc.finetune.ste``).
"""

from __future__ import annotations

import torch

from snncc.targets.loihi import chip


def _wrap(x: torch.Tensor, bits: int) -> torch.Tensor:
    half = float(1 << bits)
    return x - 2.0 * half * torch.floor((x + half) / (2.0 * half))


class LayerLoop(torch.autograd.Function):
    """apply(D, ku, kv, theta, bias, forced, cfg, *R) -> (spikes, v_pre), each (B, T, n).

    ``cfg``: (delays of R, vmin, vmax, ref_delay, slope, detach_reset); ``forced``: (B, T, n) spikes the
    recurrent synapses read instead of the layer's own, or None."""

    @staticmethod
    def forward(ctx, drive, keep_u, keep_v, theta, bias, forced, cfg, *rec):
        delays, vmin, vmax, ref_delay, slope, detach_reset = cfg
        batch, steps, n = drive.shape
        one = float(chip.DECAY_ONE)
        u = drive.new_zeros(batch, n)
        v = drive.new_zeros(batch, n)
        ref = torch.zeros(batch, n, dtype=torch.int64, device=drive.device)
        zero = drive.new_zeros(batch, n)
        spikes = drive.new_zeros(batch, steps, n)
        v_pre = drive.new_zeros(batch, steps, n)
        u_prev = drive.new_zeros(batch, steps, n)
        v_prev = drive.new_zeros(batch, steps, n)
        live = torch.zeros(batch, steps, n, dtype=torch.bool, device=drive.device)   # not refractory, not clipped
        readable = spikes if forced is None else forced
        for t in range(steps):
            q = drive[:, t]
            for d, w in zip(delays, rec):
                if t - 1 - d >= 0:
                    q = q + readable[:, t - 1 - d] @ w.T
            u_prev[:, t] = u
            v_prev[:, t] = v
            u = _wrap(torch.trunc(u * keep_u / one) + _wrap(q, chip.Q_BITS), chip.U_BITS)
            v1 = torch.trunc(v * keep_v / one) + u + bias
            v2 = torch.clamp(v1, vmin, vmax)
            refractory = ref > 0
            live[:, t] = (~refractory) & (v1 >= vmin) & (v1 <= vmax)
            v3 = torch.where(refractory, zero, v2)
            ref = torch.where(refractory, ref - 1, ref)
            s = (v3 > theta).to(drive.dtype)
            v_pre[:, t] = v3
            spikes[:, t] = s
            v = v3 * (1.0 - s)
            ref = torch.where(s > 0, torch.full_like(ref, ref_delay - 1), ref)
        ctx.save_for_backward(keep_u, keep_v, theta, spikes, v_pre, u_prev, v_prev, live,
                              forced if forced is not None else spikes, *rec)
        ctx.cfg = cfg
        ctx.forced = forced is not None
        return spikes, v_pre

    @staticmethod
    def backward(ctx, g_spikes, g_vpre):
        keep_u, keep_v, theta, spikes, v_pre, u_prev, v_prev, live, readable, *rec = ctx.saved_tensors
        delays, vmin, vmax, ref_delay, slope, detach_reset = ctx.cfg
        batch, steps, n = spikes.shape
        one = float(chip.DECAY_ONE)
        if g_spikes is None:
            g_spikes = torch.zeros_like(spikes)
        if g_vpre is None:
            g_vpre = torch.zeros_like(spikes)
        scale = theta.abs().clamp_min(1e-12)
        g_drive = torch.zeros_like(spikes)
        g_rec_in = torch.zeros_like(spikes) if (rec and not ctx.forced) else None
        g_R = [torch.zeros_like(w) for w in rec]
        g_ku = torch.zeros_like(keep_u)
        g_kv = torch.zeros_like(keep_v)
        g_theta = torch.zeros_like(theta)
        g_bias = torch.zeros(n, dtype=spikes.dtype, device=spikes.device)
        gu = spikes.new_zeros(batch, n)
        gv = spikes.new_zeros(batch, n)
        for t in range(steps - 1, -1, -1):
            s = spikes[:, t]
            v3 = v_pre[:, t]
            g_s = g_spikes[:, t]
            if g_rec_in is not None:
                g_s = g_s + g_rec_in[:, t]
            if not detach_reset:
                g_s = g_s - gv * v3
            h = 1.0 / (1.0 + slope * ((v3 - theta) / scale).abs()) ** 2 / scale
            hg = h * g_s
            g_theta = g_theta - hg.sum(0)
            g_v3 = gv * (1.0 - s) + g_vpre[:, t] + hg
            g_v1 = torch.where(live[:, t], g_v3, torch.zeros_like(g_v3))
            g_bias = g_bias + g_v1.sum(0)
            g_kv = g_kv + (g_v1 * v_prev[:, t]).sum(0) / one
            gv = g_v1 * keep_v / one
            g_u = gu + g_v1
            g_ku = g_ku + (g_u * u_prev[:, t]).sum(0) / one
            gu = g_u * keep_u / one
            g_drive[:, t] = g_u
            for k, (d, w) in enumerate(zip(delays, rec)):
                src = t - 1 - d
                if src >= 0:
                    g_R[k] = g_R[k] + g_u.T @ readable[:, src]
                    if g_rec_in is not None:
                        g_rec_in[:, src] = g_rec_in[:, src] + g_u @ w
        return (g_drive, _to_shape(g_ku, keep_u), _to_shape(g_kv, keep_v), _to_shape(g_theta, theta),
                g_bias, None, None, *g_R)


def _to_shape(g: torch.Tensor, like: torch.Tensor) -> torch.Tensor:
    return g.sum_to_size(like.shape) if like.dim() else g.sum()
