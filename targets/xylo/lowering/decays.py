"""Xylo's decays and the kernels a lowered neuron reproduces.

Xylo decays a state x by a bit shift (``dash`` d, 4 bits): x <- x - max(x >> d, sign(x)), which is
x * (1 - 2^-d) up to integer rounding. So the decays it offers are the grid ``a(d) = 1 - 2^-d``
(d = 0 gives 0: the state is cleared before it is used).

The IR LIF (alpha, beta) answers an input at step 0 with the voltage kernel
    h(n) = sum_{m=0..n} alpha^m beta^(n-m)
and its subtract reset (theta at step 0) with -theta * beta^n, n >= 1 (the IR's standard rule).

A *memoryless-readout* Xylo neuron (dash_mem 0: V = i_1 + i_2 + bias) with two synaptic currents of
decays a_1, a_2 (chip order: i_k <- a_k (i_k + w_k x)) answers with
    u_1 a_1^(n+1) + u_2 a_2^(n+1)        (weights w_k = u_k W)
and feeds its own spikes back through its recurrent self-weights rho_k (i_k += rho_k at n = 1):
    rho_1 a_1^n + rho_2 a_2^n            (n >= 1)
``two_exponential`` fits (u, rho) by weighted least squares, weights ``lam^n``; with a_1 = alpha and
a_2 = beta the fit is exact (partial fractions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DASH_MAX = 15
HORIZON = 160            # steps of kernel the fits look at
FIT_WEIGHT = 0.85        # lam: recent lags count more (measured on the Braille RSNN: 0.8-0.9 agree best)


def grid(dash) -> np.ndarray:
    """The decay a Xylo dash gives (float): 1 - 2^-d (0 for d = 0)."""
    return 1.0 - np.power(2.0, -np.asarray(dash, np.float64))


def nearest_dash(decay) -> np.ndarray:
    """The dash whose decay is nearest to ``decay`` in time constant, -1/log(a) (0 for a <= 1/4)."""
    a = np.clip(np.asarray(decay, np.float64), 0.0, 1.0 - 2.0 ** -DASH_MAX)
    cand = np.arange(1, DASH_MAX + 1)
    g = grid(cand)
    with np.errstate(divide="ignore"):
        tau = -1.0 / np.log(np.maximum(a, 1e-300))
        tg = -1.0 / np.log(g)
    best = cand[np.argmin(np.abs(np.log(tau[..., None]) - np.log(tg)), axis=-1)]
    return np.where(a <= 0.25, 0, best).astype(np.int64)


def neighbour_dashes(decay: float) -> tuple[int, int]:
    """The two dashes around ``decay`` on the grid (equal when it sits on the grid)."""
    a = float(decay)
    below = max([d for d in range(DASH_MAX + 1) if grid(d) <= a + 1e-12], default=0)
    above = min([d for d in range(DASH_MAX + 1) if grid(d) >= a - 1e-12], default=DASH_MAX)
    return int(below), int(above)


def lif_kernel(alpha: float, beta: float, n: np.ndarray) -> np.ndarray:
    """h(n) = sum_{m<=n} alpha^m beta^(n-m): the IR voltage kernel of a unit input at step 0."""
    n = np.asarray(n)
    if abs(alpha - beta) < 1e-12:
        return (n + 1) * alpha ** n
    return (alpha ** (n + 1) - beta ** (n + 1)) / (alpha - beta)


@dataclass(frozen=True)
class TwoExponential:
    dashes: tuple[int, int]
    u: tuple[float, float]      # drive coefficients: w_k = u_k * W
    rho: tuple[float, float]    # self-feedback per spike, in units of theta
    drive_error: float          # weighted relative L2 error of the drive kernel
    reset_error: float


def two_exponential(alpha: float, beta: float, dashes: tuple[int, int], lam: float = FIT_WEIGHT) -> TwoExponential:
    """Fit a memoryless-readout neuron with synapse decays ``grid(dashes)`` to the IR LIF (alpha, beta)."""
    a = grid(np.asarray(dashes))
    n = np.arange(HORIZON)
    w = lam ** n
    target = lif_kernel(alpha, beta, n)
    basis = np.stack([a[0] ** (n + 1), a[1] ** (n + 1)], 1)
    u = _weighted_lstsq(basis, target, w)
    m = n[1:]
    r_target = -(beta ** m)
    r_basis = np.stack([a[0] ** m, a[1] ** m], 1)
    rho = _weighted_lstsq(r_basis, r_target, w[1:])
    return TwoExponential(tuple(int(d) for d in dashes), (float(u[0]), float(u[1])), (float(rho[0]), float(rho[1])),
                          _rel_error(basis @ u, target, w), _rel_error(r_basis @ rho, r_target, w[1:]))


def _weighted_lstsq(basis: np.ndarray, target: np.ndarray, w: np.ndarray) -> np.ndarray:
    if np.allclose(basis[:, 0], basis[:, 1]):      # one decay twice: one exponential, split evenly
        c = np.linalg.lstsq(basis[:, :1] * w[:, None], target * w, rcond=None)[0]
        return np.array([c[0] / 2, c[0] / 2])
    return np.linalg.lstsq(basis * w[:, None], target * w, rcond=None)[0]


def _rel_error(fit: np.ndarray, target: np.ndarray, w: np.ndarray) -> float:
    den = float(np.linalg.norm(target * w))
    return float(np.linalg.norm((fit - target) * w) / den) if den else 0.0


def best_pairs(alpha: float, beta: float, count: int = 3, lam: float = FIT_WEIGHT) -> list[TwoExponential]:
    """The ``count`` dash pairs (d1 < d2, d in 1..8) whose fits have the smallest drive + reset error."""
    fits = [two_exponential(alpha, beta, (d1, d2), lam) for d1 in range(1, 9) for d2 in range(d1 + 1, 10)]
    return sorted(fits, key=lambda f: f.drive_error + f.reset_error)[:count]
