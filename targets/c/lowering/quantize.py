"""The float structure on the integer grid, by one weight rule (``options.RULES``): a ``CNetwork``.

Per population, F (fraction bits of the state) puts the largest finite threshold in [2**20, 2**21) units
(``THRESHOLD_BITS``); a non-spiking integrator (threshold +inf) takes F from its largest incoming weight. Then,
all rounding to nearest (numpy's ``rint``, ties to even):

    threshold   round(theta * 2**F), at least 1           (INT32_MAX, never reached, for +inf)
    alpha/beta  round(alpha * 2**16)                      (Q16)
    biases      round(b * 2**F), clamped to int32
    weights     per-layer: one e per projection, per-neuron: one e per projection and target neuron, the
                smallest e >= 0 with max |W| * 2**F / 2**e <= limit (127 int8, 32767 int16);
                w = round(W * 2**F / 2**e) clamped to +-limit; e capped at MAX_EXPONENT

The weights are stored as fan-out rows (n_source, n_target): dense, or as CSR rows where that takes less flash.
"""

from __future__ import annotations

import math

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.c.lowering.network import BiasTerm, CNetwork, CPopulation, CProjection, check_network
from snncc.targets.c.lowering.structure import Structure
from snncc.targets.c.options import (DECAY_BITS, MAX_EXPONENT, RULE_BITS, THRESHOLD_BITS, WEIGHT_LIMIT)

INT32_MAX = (1 << 31) - 1


def frac_bits(theta: np.ndarray, incoming: float) -> int:
    """F of a population with thresholds ``theta`` (float, +inf allowed) and largest incoming |weight|."""
    finite = theta[np.isfinite(theta)]
    scale = float(np.max(finite)) if finite.size else max(incoming, 1e-30) * 64.0
    return int(THRESHOLD_BITS - math.floor(math.log2(scale)))


def _exponents(w_units: np.ndarray, limit: int, per_neuron: bool) -> np.ndarray:
    """Per target neuron (columns of the fan-out matrix ``w_units`` in state units), the smallest e >= 0 with
    max |w| / 2**e <= limit (one e for all with ``per_neuron`` False)."""
    peak = np.abs(w_units).max(axis=0) if w_units.size else np.zeros(w_units.shape[1])
    if not per_neuron:
        peak = np.full_like(peak, peak.max(initial=0.0))
    with np.errstate(divide="ignore"):
        e = np.ceil(np.log2(np.where(peak > 0, peak / limit, 1.0)))
    return np.clip(e, 0, MAX_EXPONENT).astype(np.int64)


def dense_or_sparse(weights: np.ndarray, index_bytes: int, bits: int) -> str:
    """The layout that takes less flash: dense rows, or CSR (a 4-byte row pointer per source, an index and a
    weight per nonzero)."""
    n_src, n_tgt = weights.shape
    dense = n_src * n_tgt * bits // 8
    nnz = int(np.count_nonzero(weights))
    sparse = 4 * (n_src + 1) + nnz * (index_bytes + bits // 8)
    return "sparse" if sparse < dense else "dense"


def quantize(st: Structure, rule: str, steps: int) -> CNetwork:
    """The ``CNetwork`` of ``st`` by ``rule`` (one of ``options.CANDIDATES``)."""
    bits = RULE_BITS[rule]
    limit = WEIGHT_LIMIT[bits]
    per_neuron = rule.startswith("per-neuron")
    pops: list[CPopulation] = []
    for i, fp in enumerate(st.populations):
        op = fp.op
        incoming = max((float(abs(q.matrix).max()) for q in st.projections if q.target == i and q.matrix.nnz),
                       default=1.0)
        theta = np.asarray(op.threshold, np.float64)
        f = frac_bits(theta, incoming)
        unit = 2.0 ** f
        fires = bool(np.all(np.isfinite(theta)))
        if not fires and np.any(np.isfinite(theta)):
            raise SnnccError("mixes finite and infinite thresholds; the C target takes one or the other per "
                             "population", field=f"node '{fp.name}'")
        th = np.full(op.n, INT32_MAX, np.int64) if not fires else np.rint(theta * unit).astype(np.int64)
        th = np.maximum(th, 1)

        def q16(a: np.ndarray) -> np.ndarray:
            return np.rint(np.asarray(a, np.float64) * (1 << DECAY_BITS)).astype(np.int64)

        def state(b: np.ndarray) -> np.ndarray:
            return np.clip(np.rint(np.asarray(b, np.float64) * unit), -(1 << 31), INT32_MAX).astype(np.int64)

        pops.append(CPopulation(
            name=fp.name, n=op.n, frac_bits=f, threshold=th, alpha=q16(fp.alpha), beta=q16(fp.beta),
            reset=op.reset, refractory=int(op.refractory), fire_test=op.fire_test, max_spikes=int(op.max_spikes),
            bias_v=None if fp.bias_v is None else state(fp.bias_v),
            bias_i=[BiasTerm(int(start), state(vec)) for start, vec in fp.bias_i], fires=fires))
    projs: list[CProjection] = []
    for fq in st.projections:
        target = pops[fq.target]
        m = fq.matrix.T.tocsr()                                   # (n_src, n_tgt) fan-out rows, float
        unit = 2.0 ** target.frac_bits
        peak = np.zeros(m.shape[1])
        if m.nnz:
            np.maximum.at(peak, m.indices, np.abs(m.data) * unit)
        e = _exponents(peak[None, :], limit, per_neuron)
        w = np.zeros(m.shape, np.int16)
        rows = np.repeat(np.arange(m.shape[0]), np.diff(m.indptr))
        w[rows, m.indices] = np.clip(np.rint(m.data * unit / np.exp2(e[m.indices])), -limit, limit).astype(np.int16)
        index_bytes = 2 if target.n <= 65535 else 4
        projs.append(CProjection(source=fq.source, target=fq.target, delay=int(fq.delay), bits=bits, weights=w,
                                 exponent=e, layout=dense_or_sparse(w, index_bytes, bits), origin=fq.origin))
    net = CNetwork(dt=float(st.dt), inputs=st.inputs, populations=pops, projections=projs, output=st.output,
                   rule=rule, steps=int(steps), names={"input": st.input_name, "readout": st.readout})
    check_network(net)
    return net


def float_reading(net: CNetwork, p: int) -> dict[str, np.ndarray]:
    """Population ``p``'s integers read back in the model's units: threshold, alpha, beta (Q16 / 2**16)."""
    pop = net.populations[p]
    unit = 2.0 ** -pop.frac_bits
    return {"threshold": np.where(pop.fires, pop.threshold * unit, np.inf), "alpha": pop.alpha / 2.0 ** DECAY_BITS,
            "beta": pop.beta / 2.0 ** DECAY_BITS}


def float_weights(net: CNetwork, q: CProjection) -> np.ndarray:
    """A projection's weights read back in the model's units, as the IR's (n_target, n_source) matrix."""
    unit = 2.0 ** -net.populations[q.target].frac_bits
    return (q.weights.astype(np.float64) * np.exp2(q.exponent)[None, :] * unit).T


__all__ = ["quantize", "frac_bits", "dense_or_sparse", "float_reading", "float_weights"]
