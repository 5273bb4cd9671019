"""Exact search, lower bound and output-axon repair.

Exact search (small all-dense networks with one profile per layer, at most DP_MAX_STATES count
vectors): a dynamic programme over "how many neurons of each layer on each core". F[m] = one core
can hold m_i neurons of each layer i (neurons, synapse bits, input axons, profiles; output axons
relaxed); cover_k = cover_(k-1) (+) maximal configs of F; the first k whose cover reaches n is the
minimum number of cores, and backtracking gives a map that is used when it beats packing.

Lower bound = max(total neurons / neurons per core, synapse bits at the best possible chunk fill /
core memory, threshold and compartment profiles / per core, each all-dense layer's own minimum,
the exact search when run). It ignores axon limits of sparse layers (weak for random ones).

Repair: pack; a core over its output axons gets the layer with most neurons on it cut into
max(k + 1, ceil(k * overuse)) slices; repack, at most MAX_REPAIRS times.
"""

from __future__ import annotations

import math

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.loihi.mapping.packing import assignment, in_network_order, make_slices, pack
from snncc.targets.loihi.mapping.projections import NetworkModel
from snncc.targets.loihi.mapping.resources import LIMIT_TITLES, min_bits_per_synapse
from snncc.targets.loihi.mapping.slicing import dense_bits_curve, layer_slices
from snncc.targets.loihi.mapping.usage import RATIO_KEYS, core_usage, worst_ratio

DP_MAX_STATES = 400_000
DP_MAX_WORK = 4e8
MAX_REPAIRS = 64


def _dp_applicable(model: NetworkModel) -> bool:
    idx = range(1, len(model.layers))
    if not all(model.all_full(i) and model.uniform_profiles(i) for i in idx):
        return False
    states = math.prod(model.layers[i].n + 1 for i in idx)
    return states <= DP_MAX_STATES and len(model.layers) - 1 <= 8


def _any(arrays):
    """Elementwise OR of arrays that broadcast against each other."""
    out = arrays[0]
    for a in arrays[1:]:
        out = out | a
    return out


def _dp_feasible_configs(model: NetworkModel) -> np.ndarray:
    """Boolean grid F[m_1, ..., m_L]: can one core hold m_i neurons of each layer i (alone)?"""
    chip = model.chip
    limits = chip.limits()
    idx = list(range(1, len(model.layers)))
    shape = tuple(model.layers[i].n + 1 for i in idx)
    grids = np.meshgrid(*[np.arange(s, dtype=np.int64) for s in shape], indexing="ij", sparse=True)
    neurons = sum(grids)
    bits = sum(dense_bits_curve(model, i, model.layers[i].n)[g] for i, g in zip(idx, grids))
    present = {i: g > 0 for i, g in zip(idx, grids)}
    axons = 0
    for s in range(len(model.layers)):
        feeders = [i for i in idx if s in model.src_layers(i)]
        if feeders:
            axons = axons + model.layers[s].n * _any([present[i] for i in feeders])
    ok = (neurons <= limits["neurons"]) & (bits <= limits["synapse_bits"]) & (axons <= limits["input_axons"])
    for name, keys in (("vth_profiles", model.vth_key), ("compartment_profiles", model.cx_key),
                       ("voltage_limits", model.vlim_key)):
        count = 0
        layer_key = {i: int(model.layer_keys(i)[("vth_profiles", "compartment_profiles", "voltage_limits").index(name)][0])
                     for i in idx}
        for key in sorted(set(layer_key.values())):
            count = count + _any([present[i] for i in idx if layer_key[i] == key])
        ok = ok & (count <= limits[name])
    return np.broadcast_to(ok, shape).copy()


def dp_min_cores(model: NetworkModel, max_cores: int = 100_000):
    """Minimum cores over all count assignments (output axons relaxed); (K, configs per core) or None."""
    if not _dp_applicable(model):
        return None
    feasible = _dp_feasible_configs(model)
    shape = feasible.shape
    maximal = feasible.copy()
    for ax in range(feasible.ndim):
        nxt = np.zeros_like(feasible)
        src = [slice(None)] * feasible.ndim
        dst = [slice(None)] * feasible.ndim
        src[ax], dst[ax] = slice(1, None), slice(0, -1)
        nxt[tuple(dst)] = feasible[tuple(src)]
        maximal &= ~nxt
    configs = np.argwhere(maximal)
    configs = configs[configs.sum(axis=1) > 0]
    if configs.size == 0 or configs.shape[0] * feasible.size > DP_MAX_WORK:
        return None
    target = tuple(s - 1 for s in shape)
    history = [feasible]
    cover = feasible
    aranges = [np.arange(s) for s in shape]
    while not cover[target]:
        if len(history) >= max_cores or len(history) * configs.shape[0] * cover.size > 50 * DP_MAX_WORK:
            return None
        nxt = np.zeros_like(cover)
        for f in configs:
            nxt |= cover[np.ix_(*[np.maximum(a - fi, 0) for a, fi in zip(aranges, f)])]
        if np.array_equal(nxt, cover):
            return None
        history.append(nxt)
        cover = nxt
    k = len(history)
    # backtrack: a config per core
    x = np.array(target)
    chosen = []
    for j in range(k - 1, 0, -1):
        for f in configs:
            rest = np.maximum(x - f, 0)
            if history[j - 1][tuple(rest)]:
                chosen.append(np.minimum(f, x))
                x = rest
                break
    chosen.append(x.copy())
    return k, [c for c in chosen if c.sum() > 0]


def dp_cores(model: NetworkModel, configs) -> list[list[tuple[int, int, int]]]:
    """The exact search's neurons-per-layer configs as (layer, start, stop) slices, filled front to back."""
    idx = list(range(1, len(model.layers)))
    start = {i: 0 for i in idx}
    cores = []
    for conf in configs:
        core = []
        for i, m in zip(idx, conf):
            if m:
                core.append((i, start[i], start[i] + int(m)))
                start[i] += int(m)
        cores.append(core)
    return cores


def lower_bound(model: NetworkModel, layer_minimum: dict[int, int], dp: int | None) -> tuple[int, str]:
    """(bound, the reasons that reach it): the largest of the bounds in the module docstring."""
    chip = model.chip
    limits = chip.limits()
    n_total = sum(model.layers[i].n for i in range(1, len(model.layers)))
    bits = sum(p.nnz * min_bits_per_synapse(p.bits_per_weight, chip) for p in model.projections)
    candidates = [
        (-(-n_total // limits["neurons"]), f"{n_total:,} neurons / {limits['neurons']:,} per core"),
        (math.ceil(bits / limits["synapse_bits"] - 1e-9), "synapse bits at the best chunk fill / core memory"),
        (-(-(int(model.vth_key.max(initial=0)) + 1) // limits["vth_profiles"]), "threshold profiles"),
        (-(-(int(model.cx_key.max(initial=0)) + 1) // limits["compartment_profiles"]), "compartment profiles"),
    ]
    for i, k in layer_minimum.items():
        candidates.append((k, f"layer '{model.layers[i].name}' alone needs {k}"))
    if dp is not None:
        candidates.append((dp, "exact search over neurons per layer per core (output axons relaxed)"))
    best = max(c[0] for c in candidates)
    reasons = [r for k, r in candidates if k == best]
    return int(best), "; ".join(reasons)


def pack_and_repair(model: NetworkModel, bounds: dict[int, np.ndarray], why: dict[int, str], dp):
    """Pack the slices (or take the exact search's map when it has fewer cores and fits), then cut a
    layer finer wherever a core is over its output axons, until none is.

    Returns (cores as lists of (layer, start, stop) in network order, per-core usage arrays,
    the slice boundaries used, what limits each layer's slicing).
    """
    limits = model.chip.limits()
    forced, why = dict(bounds), dict(why)
    for _ in range(MAX_REPAIRS):
        packed = pack(model, make_slices(model, forced))
        cores = in_network_order([[(q.layer, q.start, q.stop) for q in c.slices] for c in packed])
        if dp and dp[0] < len(cores):
            dp_layout = in_network_order(dp_cores(model, dp[1]))
            usage = core_usage(model, assignment(model, dp_layout), len(dp_layout))
            if worst_ratio(usage, model.chip, RATIO_KEYS + ("output_axons",))[0] <= 1.0:
                cores = dp_layout
        core_of = assignment(model, cores)
        usage = core_usage(model, core_of, len(cores))
        over = np.flatnonzero(usage["output_axons"] > limits["output_axons"])
        if over.size == 0:
            return cores, usage, forced, why
        bump: dict[int, float] = {}
        for c in over.tolist():
            # the layer with the most neurons on that core is cut finer (fewer sources per core)
            i = max(sorted({j for j, _, _ in cores[c]}), key=lambda j: int(np.count_nonzero(core_of[j] == c)))
            bump[i] = max(bump.get(i, 1.0), usage["output_axons"][c] / limits["output_axons"])
        for i, factor in sorted(bump.items()):
            k_now = len(forced[i]) - 1
            if k_now >= model.layers[i].n:
                raise SnnccError(f"{LIMIT_TITLES['output_axons']}: needs more than {limits['output_axons']:,} "
                                 "with one neuron per core; no map exists", field=f"layer '{model.layers[i].name}'")
            k_new = min(model.layers[i].n, max(k_now + 1, math.ceil(k_now * factor)))
            forced[i], _ = layer_slices(model, i, at_least=k_new)
            why[i] = f"output axons (cut into {len(forced[i]) - 1} slices)"
    raise SnnccError(f"{LIMIT_TITLES['output_axons']}: still exceeded after {MAX_REPAIRS} repairs",
                     field="core map")
