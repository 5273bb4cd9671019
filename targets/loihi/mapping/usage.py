"""Per-core usage of an assignment of neurons to cores, counted as the chip's rules state it.

For each core (resources.py):

    neurons        = neurons assigned to it
    input axons    = distinct source neurons with a nonzero synapse on the core (one axon serves
                     every projection from that source into the core)
    synapse bits   = sum over (source, projection) of that axon's synapse list into the core,
                     chunked (<= 64 synapses, n*b + 10 bits rounded to 64 bits; zeros need no synapse)
    output axons   = (source neuron on the core, destination core) pairs, charged to the source's core
    vth / compartment profiles / voltage limits = distinct profile keys of its neurons

Counted in one O(synapses) pass per projection (numba, ``kernels.py``) when a layer's cores
ascend with its neurons, else through (core, source) pairs. ``estimate/energy.py`` reads the same pairs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.loihi.mapping.kernels import pair_usage
from snncc.targets.loihi.mapping.projections import NetworkModel, Projection
from snncc.targets.loihi.mapping.resources import ChipSpec, axon_list_bits, list_bits

RATIO_KEYS = ("neurons", "input_axons", "synapse_bits", "vth_profiles", "compartment_profiles", "voltage_limits")

_TABLES: dict = {}


def pair_bits(count: np.ndarray, n_range: np.ndarray, bits_per_weight: int, chip: ChipSpec) -> np.ndarray:
    """``axon_list_bits`` through lookup tables (ranges up to a core's compartments), same values."""
    cap = chip.compartments_per_core
    if count.size == 0 or int(n_range.max()) > cap:
        return axon_list_bits(count, n_range, bits_per_weight, chip)
    return bits_table(bits_per_weight, chip)[n_range, count]


def bits_table(bits_per_weight: int, chip: ChipSpec) -> np.ndarray:
    """axon_list_bits for every (range size, count) up to a core's compartments: table[range, count]."""
    key = (chip, bits_per_weight)
    if key not in _TABLES:
        m = np.arange(chip.compartments_per_core + 1, dtype=np.int64)
        _TABLES[key] = np.ascontiguousarray(axon_list_bits(m[None, :], m[:, None], bits_per_weight, chip))
    return _TABLES[key]


def _sparse_pairs(p: Projection, cores_dst: np.ndarray):
    """(dst core, source, count) of distinct (core, source) pairs of a sparse projection."""
    if p.nnz == 0:
        z = np.zeros(0, np.int64)
        return z, z, z
    if cores_dst.size < 2 or np.all(cores_dst[1:] >= cores_dst[:-1]):
        # CSC order: within a source's run destinations ascend, so cores ascend: no sort needed
        c = cores_dst[p.cidx]
        change = np.empty(c.size, bool)
        change[0] = True
        np.not_equal(c[1:], c[:-1], out=change[1:])
        col_start = p.cptr[:-1][np.diff(p.cptr) > 0]
        change[col_start] = True
        starts = np.flatnonzero(change)
        del change
        count = np.diff(np.append(starts, c.size))
        col = np.repeat(np.arange(p.n_pre, dtype=np.int32), np.diff(p.cptr))
        src = col[starts]
        del col
        return c[starts].astype(np.int64, copy=False), src.astype(np.int64), count.astype(np.int64, copy=False)
    key = cores_dst[p.post] * np.int64(p.n_pre) + p.pre
    uk, count = np.unique(key, return_counts=True)
    dst, src = np.divmod(uk, np.int64(p.n_pre))
    return dst, src, count.astype(np.int64)


def projection_pairs(model: NetworkModel, p: Projection, cores_dst: np.ndarray, n_cores: int):
    """(dst core, global source, count, bits) of one projection under a core assignment of its layer."""
    m_core = np.bincount(cores_dst, minlength=n_cores)
    if p.full:
        cores = np.flatnonzero(m_core)
        dst = np.repeat(cores, p.n_pre)
        src = np.tile(np.arange(p.n_pre, dtype=np.int64), cores.size)
        count = m_core[dst]
        bits = list_bits(count, p.bits_per_weight, model.chip)
    else:
        dst, src, count = _sparse_pairs(p, cores_dst)
        bits = pair_bits(count, m_core[dst], p.bits_per_weight, model.chip)
    return dst, src + model.offset[p.src], count, bits


@dataclass
class PairTable:
    """One row per (destination core, global source neuron, projection): synapse count and bits."""

    proj: np.ndarray
    dst_core: np.ndarray
    src: np.ndarray
    count: np.ndarray
    bits: np.ndarray


def pair_table(model: NetworkModel, core_of: dict[int, np.ndarray], n_cores: int,
               layers: set[int] | None = None) -> PairTable:
    """All (core, source, projection) rows at once (small networks; core_usage streams instead)."""
    parts = []
    for pid, p in enumerate(model.projections):
        if layers is not None and p.dst not in layers:
            continue
        dst, src, count, bits = projection_pairs(model, p, core_of[p.dst], n_cores)
        parts.append((np.full(dst.size, pid, np.int64), dst, src, count, bits))
    if not parts:
        z = np.zeros(0, np.int64)
        return PairTable(z, z, z, z, z)
    return PairTable(*(np.concatenate([q[j] for q in parts]).astype(np.int64) for j in range(5)))


def _distinct_per_core(core: np.ndarray, key: np.ndarray, n_cores: int, n_keys: int) -> np.ndarray:
    if core.size == 0:
        return np.zeros(n_cores, np.int64)
    uk = np.unique(core * np.int64(n_keys) + key)
    return np.bincount(uk // n_keys, minlength=n_cores).astype(np.int64)


def _distinct_pairs(cores: list[np.ndarray], srcs: list[np.ndarray], n_cores: int, n_global: int):
    """The distinct (core, global source) pairs of several projections from one source layer, sorted by key
    (what ``np.unique`` of core * n_global + source gives): through a presence table over the keys the sources
    span (linear) when it is small, else by sorting."""
    lo = min(int(s.min(initial=n_global)) for s in srcs)
    hi = max(int(s.max(initial=-1)) for s in srcs) + 1
    width = max(hi - lo, 0)
    if 0 < n_cores * width <= 1 << 27:
        seen = np.zeros(n_cores * width, bool)
        for c, s in zip(cores, srcs):
            seen[c * np.int64(width) + (s - lo)] = True
        key = np.flatnonzero(seen)
        a_core, a_src = np.divmod(key, np.int64(width))
        return a_core, a_src + lo
    key = np.unique(np.concatenate([c * np.int64(n_global) + s for c, s in zip(cores, srcs)]))
    return np.divmod(key, np.int64(n_global))


def core_usage(model: NetworkModel, core_of: dict[int, np.ndarray], n_cores: int,
               layers: set[int] | None = None) -> dict[str, np.ndarray]:
    """Per-core usage arrays (length n_cores) of every resource for the assignment ``core_of``.

    Streams over source layers: one source's (core, source) pairs at a time, merged only when a
    source feeds several projections (an axon serves all of them), so memory stays ~ one projection.
    """
    layers = set(core_of) if layers is None else layers
    neurons = np.zeros(n_cores, np.int64)
    global_core = np.full(model.n_global, -1, np.int64)
    for i in layers:
        neurons += np.bincount(core_of[i], minlength=n_cores)
        global_core[model.offset[i]:model.offset[i] + model.layers[i].n] = core_of[i]
    bits = np.zeros(n_cores, np.int64)
    axons = np.zeros(n_cores, np.int64)
    out_axons = np.zeros(n_cores, np.int64)
    by_src: dict[int, list] = {}
    for p in model.projections:
        if p.dst in layers:
            by_src.setdefault(p.src, []).append(p)
    for src_layer, projs in sorted(by_src.items()):
        p0 = projs[0]
        if (len(projs) == 1 and not p0.full and core_of[p0.dst].size
                and np.all(core_of[p0.dst][1:] >= core_of[p0.dst][:-1])
                and core_of[p0.dst].size <= model.chip.compartments_per_core * n_cores):
            m_core = np.bincount(core_of[p0.dst], minlength=n_cores)
            if int(m_core.max()) <= model.chip.compartments_per_core:
                a, b, o = pair_usage(p0.cptr, p0.cidx, core_of[p0.dst], m_core,
                                     bits_table(p0.bits_per_weight, model.chip),
                                     global_core[model.offset[src_layer]:model.offset[src_layer] + p0.n_pre], n_cores)
                axons += a
                bits += b
                out_axons += o
                continue
        cores, srcs = [], []
        for p in projs:
            dst, src, _, b = projection_pairs(model, p, core_of[p.dst], n_cores)
            bits += np.bincount(dst, weights=b, minlength=n_cores).astype(np.int64)
            cores.append(dst)
            srcs.append(src)
            del b
        if len(projs) == 1:
            a_core, a_src = cores[0], srcs[0]
        else:
            a_core, a_src = _distinct_pairs(cores, srcs, n_cores, model.n_global)
        del cores, srcs
        axons += np.bincount(a_core, minlength=n_cores)
        # output axons: one per (source neuron, destination core), charged to the source's core
        sc = global_core[a_src]
        sc = sc[sc >= 0]
        out_axons += np.bincount(sc, minlength=n_cores)
    usage = {"neurons": neurons, "input_axons": axons, "synapse_bits": bits, "output_axons": out_axons}
    cores_all = np.concatenate([core_of[i] for i in sorted(layers)]) if layers else np.zeros(0, np.int64)
    for name, keys in (("vth_profiles", model.vth_key), ("compartment_profiles", model.cx_key),
                       ("voltage_limits", model.vlim_key)):
        k = np.concatenate([keys[model.neuron_offset[i - 1]:model.neuron_offset[i - 1] + model.layers[i].n]
                            for i in sorted(layers)]) if layers else np.zeros(0, np.int64)
        usage[name] = _distinct_per_core(cores_all, k, n_cores, int(keys.max(initial=0)) + 1)
    return usage


def worst_ratio(usage: dict[str, np.ndarray], chip: ChipSpec, keys=RATIO_KEYS) -> tuple[float, str]:
    """Largest usage / limit over cores and resources, and that resource (settings count only when over)."""
    limits = chip.limits()
    worst, which = 0.0, "neurons"
    for k in keys:
        r = float(usage[k].max(initial=0)) / limits[k]
        if k in ("vth_profiles", "compartment_profiles", "voltage_limits") and r <= 1.0:
            continue
        if r > worst:
            worst, which = r, k
    return worst, which


def range_usage(model: NetworkModel, i: int, a: int, z: int) -> dict[str, int]:
    """Usage of neurons a..z-1 of layer i alone on a core (no output axons: they depend on others)."""
    m = z - a
    axons, bits = [], 0
    sources: dict[int, np.ndarray] = {}          # source layer -> which of its neurons have a synapse here
    for p in model.into[i]:
        used = sources.setdefault(p.src, np.zeros(p.n_pre, bool))
        if p.full:
            used[:] = True
            bits += p.n_pre * int(list_bits(m, p.bits_per_weight, model.chip))
            continue
        # synapses per source in rows a..z-1: a count per source (linear), not a sort
        cnt = np.bincount(p.indices[p.indptr[a]:p.indptr[z]], minlength=p.n_pre)
        has = cnt > 0
        used |= has
        cnt = cnt[has]
        bits += int(pair_bits(cnt, np.full(cnt.size, m, np.int64), p.bits_per_weight, model.chip).sum())
    n_axons = sum(int(np.count_nonzero(used)) for used in sources.values())
    out = {"neurons": m, "input_axons": int(n_axons), "synapse_bits": int(bits)}
    for name, keys in zip(("vth_profiles", "compartment_profiles", "voltage_limits"), model.layer_keys(i)):
        k = keys[a:z]
        out[name] = 1 if k.size and k.min() == k.max() else int(np.unique(k).size)
    return out
