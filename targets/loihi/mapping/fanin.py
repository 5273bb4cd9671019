"""Fan-in wider than a core's input axons: insert a relay layer (the transformed network is what runs).

A compartment receives synapses only through its own core's input axons (4,096 on Loihi 1);
multi-compartment joins (dendritic accumulation) combine compartments of the *same* core, so they
do not raise that limit. Spikes carry one bit, so K axons carry at most K bits per step, while the
input of a neuron with F generic weights carries F bits (all 2**F spike patterns give different
sums): no relay scheme can pass the exact input of more than 4,096 sources through 4,096 axons in
the same step. Exact fan-in splitting is therefore impossible on Loihi 1; what snncc does:

    relay layer R (inserted before the wide layer L, parameters iDecay 4096, vDecay 0, refDelay 1):
      copy relays    one per source for the K most important sources (largest sum |w| over L):
                     weight 254, threshold below it, so a relay spikes exactly when its source
                     did, one step later. EXACT; the step is taken back from the projection's
                     synaptic delay when it has one (then timing is exact too), else +1 step.
      rate relays    for each neuron of L and each group of <= 4,096 remaining sources, a pair
                     (positive weights, negated negative weights) of non-leaky integrate-and-fire
                     compartments with threshold omega; L listens with weight +omega / -omega.
                     LOSSY: residuals below omega wait, the excess above omega is lost at a spike
                     (Loihi 1 resets v to 0), at most one quantum omega per step is passed.
    L then listens to R only: K + 2 * groups * (neurons of L on the core) axons per core.

The record returned says how many sources went each way; the map and the report print it, and the
emulated network is the transformed one.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.loihi.chip import DECAY_ONE, WEIGHT_MAX
from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork
from snncc.targets.loihi.mapping.resources import LOIHI1, ChipSpec, axon_list_bits, delay_bits, list_bits

COPY_WEIGHT = WEIGHT_MAX             # a copy relay's weight: the largest (254), its threshold below it
MAX_QUANTUM = WEIGHT_MAX - 2         # the rate relays' quantum omega: even, 2..252


def _dense(weight) -> np.ndarray:
    if hasattr(weight, "toarray"):
        return np.asarray(weight.toarray())
    return np.asarray(weight)


def row_fan_in(layer: LoihiLayer) -> np.ndarray:
    """Nonzero synapses into each neuron of ``layer`` (feed-forward plus recurrent)."""
    def nnz_rows(w):
        if w is None:
            return np.zeros(layer.n, np.int64)
        if hasattr(w, "getnnz"):
            return np.asarray(w.getnnz(axis=1), np.int64)
        return np.count_nonzero(np.asarray(w), axis=1).astype(np.int64)

    return nnz_rows(layer.weight) + nnz_rows(layer.weight_rec)


def _uniform_delay(layer: LoihiLayer) -> int:
    d = np.asarray(layer.delay)
    if d.ndim and d.size and not np.all(d == d.flat[0]):
        raise SnnccError(f"input axons (fan-in) per core: layer '{layer.name}' needs relays, which "
                         "need one delay for the whole projection; this layer has per-synapse delays",
                         field=f"layer '{layer.name}'")
    return int(d.flat[0]) if d.size else 0


def _targets_per_core(n_src: int, n_dst: int, bpw: int, chip: ChipSpec) -> tuple[int, int, int]:
    """Largest m (neurons of L per core) the relayed projection allows; returns (m, K copies, groups)."""
    limit_axons, limit_bits = chip.input_axons_per_core, chip.synapse_bits_per_core
    best = None
    for m in range(1, min(n_dst, chip.compartments_per_core) + 1):
        groups = 1
        while True:
            k = limit_axons - 2 * groups * m
            if k < 0:
                break
            need = math.ceil(max(n_src - k, 0) / limit_axons)
            if need <= groups:
                break
            groups = need
        if k < 0:
            break
        bits = k * int(list_bits(m, bpw, chip)) + 2 * groups * m * int(axon_list_bits(1, m, bpw, chip))
        if bits > limit_bits:
            break
        best = (m, min(k, n_src), groups)
    if best is None:
        raise SnnccError(f"synapse memory bits per core: even one relayed neuron of {n_src:,} inputs "
                         f"does not fit {limit_bits:,} bits", field="fan-in")
    return best


def relay_layer(layer: LoihiLayer, chip: ChipSpec = LOIHI1) -> tuple[LoihiLayer, LoihiLayer, dict]:
    """(relay layer R, rewired layer L, record) for a feed-forward layer whose fan-in is too wide."""
    w = _dense(layer.weight).astype(np.int64)
    n_dst, n_src = w.shape
    d = _uniform_delay(layer)
    d_target = max(d - 1, 0)
    bpw = chip.weight_bits + delay_bits(d_target)
    _, k, groups = _targets_per_core(n_src, n_dst, bpw, chip)
    importance = np.abs(w).sum(axis=0)
    order = np.argsort(-importance, kind="stable")
    copied, rest = order[:k], order[k:]
    cap = chip.input_axons_per_core
    group_of = [rest[g * cap:(g + 1) * cap] for g in range(groups)]
    rest_w = np.abs(w[:, rest])
    nz = rest_w[rest_w > 0]
    omega = int(np.clip(2 * round(float(np.median(nz)) / 2) if nz.size else 2, 2, MAX_QUANTUM))
    if np.ndim(layer.wgt_exp):
        raise SnnccError("relaying a projection with per-synapse weight exponents is not supported",
                         field=f"layer '{layer.name}'")
    e = int(layer.wgt_exp)
    if e < 0:
        step = 2 ** (-e)
        omega = max(step, (omega // step) * step)
        threshold = omega >> (-e)
    else:
        threshold = omega << e
    n_relay = k + 2 * groups * n_dst
    w_r = np.zeros((n_relay, n_src), np.int16)
    w_r[np.arange(k), copied] = COPY_WEIGHT
    w_l = np.zeros((n_dst, n_relay), np.int16)
    w_l[:, :k] = w[:, copied]
    clipped = 0
    for t in range(n_dst):
        for g, src in enumerate(group_of):
            row = k + 2 * (t * groups + g)
            pos = np.maximum(w[t, src], 0)
            neg = np.maximum(-w[t, src], 0)
            clipped += int(np.count_nonzero(neg > COPY_WEIGHT))
            w_r[row, src] = pos
            w_r[row + 1, src] = np.minimum(neg, COPY_WEIGHT)
            w_l[t, row], w_l[t, row + 1] = omega, -omega
    relay = LoihiLayer(name=f"{layer.name}.relay", kind="dense", n=n_relay, weight=w_r, wgt_exp=e,
                       delay=0, v_th_mant=int(threshold), i_decay=DECAY_ONE, v_decay=0, ref_delay=1,
                       vmin=layer.vmin, vmax=layer.vmax)
    rewired = replace(layer, weight=w_l, delay=d_target)
    exact_timing = d >= 1
    record = {
        "layer": layer.name, "relay_layer": relay.name, "method": "relay layer (copy + rate relays)",
        "fan_in": int(n_src), "copied_exactly": int(k), "through_rate_relays": int(n_src - k),
        "rate_relay_groups_per_neuron": int(groups), "relay_neurons": int(n_relay), "quantum": omega,
        "negative_weights_clipped": clipped,
        "timing": ("exact: the relay step replaces one step of the projection's delay" if exact_timing
                   else "+1 step on this projection (the relay's delivery; the projection had no delay to absorb it)"),
        "accuracy": ("exact" if n_src == k else
                     f"{n_src - k} of {n_src} sources pass through rate relays (quantum {omega}): lossy"),
        "timing_shift_steps": 0 if exact_timing else 1,
    }
    return relay, rewired, record


def split_wide_fan_in(network: LoihiNetwork, chip: ChipSpec = LOIHI1) -> tuple[LoihiNetwork, list[dict]]:
    """The network with a relay layer before every feed-forward layer whose fan-in exceeds a core's axons."""
    limit = chip.input_axons_per_core
    layers = [network.layers[0]]
    records: list[dict] = []
    for layer in network.layers[1:]:
        fan = row_fan_in(layer)
        widest = int(fan.max()) if fan.size else 0
        if widest <= limit:
            layers.append(layer)
            continue
        if layer.weight_rec is not None:
            raise SnnccError(
                f"input axons (fan-in) per core: a neuron listens to {widest:,} sources (feed-forward "
                f"plus recurrent), limit {limit:,}; relays inside a recurrent loop would change its "
                "timing, so snncc does not split recurrent fan-in", field=f"layer '{layer.name}'")
        relay, rewired, record = relay_layer(layer, chip)
        layers.extend([relay, rewired])
        records.append(record)
    if not records:
        return network, []
    meta = dict(network.metadata)
    meta["fan_in_relays"] = records
    out = LoihiNetwork(layers=layers, t_sample=network.t_sample, metadata=meta, core_map=None)
    return out, records
