"""First-fit-decreasing packing of layer slices onto cores.

Slices, largest first (by their largest share of neurons, synapse bits or input axons), each go
onto the first open core where all still fit: neurons and synapse bits add up; input axons are
the union of the slices' sources (slices fed by the same source layer may share axons); profile
keys are the union of theirs; a core holds at most one slice per layer. Else a new core opens.
Candidates: the last PACK_WINDOW cores plus the cores fed by one of the slice's source layers
(plain first fit over all cores for maps of up to PACK_WINDOW cores). Cores are then numbered in
network order (by their first slice), so neighbouring layers sit on nearby cores.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.loihi.mapping.projections import NetworkModel
from snncc.targets.loihi.mapping.slicing import equal_bounds
from snncc.targets.loihi.mapping.usage import core_usage

PACK_WINDOW = 512               # packing looks back this many cores (plus cores sharing a source layer)


@dataclass
class PackSlice:
    """One slice as packing sees it: its size, bits and axons alone on a core, its source layers and profile keys."""

    layer: int
    start: int
    stop: int
    neurons: int
    bits: int
    n_axons: int
    sources: frozenset       # layers feeding it (slices fed by different layers share no axon)
    vth: frozenset
    cx: frozenset
    vlim: frozenset
    size_key: float = 0.0


def _slice_axons(model: NetworkModel, sl: PackSlice) -> np.ndarray:
    """Sorted global ids of the sources with a nonzero synapse onto the slice."""
    parts = []
    for p in model.into[sl.layer]:
        if p.full:
            parts.append(np.arange(p.n_pre, dtype=np.int64) + model.offset[p.src])
        else:
            parts.append(p.indices[p.indptr[sl.start]:p.indptr[sl.stop]].astype(np.int64) + model.offset[p.src])
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)


def make_slices(model: NetworkModel, bounds: dict[int, np.ndarray]) -> list[PackSlice]:
    """Every slice of every layer (``bounds[i]``: boundaries of layer i) with its usage alone on a core."""
    chip = model.chip
    limits = chip.limits()
    out: list[PackSlice] = []
    for i, b in bounds.items():
        k = len(b) - 1
        ids = np.repeat(np.arange(k, dtype=np.int64), np.diff(b))
        usage = model.usage_cache.get((i, k))
        if usage is None or not np.array_equal(b, equal_bounds(model.layers[i].n, k)):
            usage = core_usage(model, {i: ids}, k, layers={i})
        vth, cx, vlim = model.layer_keys(i)
        sources = frozenset(model.src_layers(i))
        for s in range(k):
            a, z = int(b[s]), int(b[s + 1])
            sl = PackSlice(i, a, z, z - a, int(usage["synapse_bits"][s]), int(usage["input_axons"][s]), sources,
                        frozenset(np.unique(vth[a:z]).tolist()), frozenset(np.unique(cx[a:z]).tolist()),
                        frozenset(np.unique(vlim[a:z]).tolist()))
            sl.size_key = max(sl.neurons / limits["neurons"], sl.bits / limits["synapse_bits"],
                              sl.n_axons / limits["input_axons"])
            out.append(sl)
    return out


class PackedCore:
    """A core being filled: its slices and the union of their profile keys."""

    def __init__(self):
        self.slices: list[PackSlice] = []
        self.vth, self.cx, self.vlim = set(), set(), set()

    def axons(self, model: NetworkModel) -> np.ndarray:
        return np.unique(np.concatenate([_slice_axons(model, s) for s in self.slices]))


def pack(model: NetworkModel, slices: list[PackSlice]) -> list[PackedCore]:
    """First-fit decreasing: each slice (largest first) onto the first open core it fits, else a new core.

    Candidates: the last PACK_WINDOW cores opened plus every core fed by one of the slice's source
    layers (for networks of up to PACK_WINDOW cores this is plain first fit over all cores). Cheap
    necessary conditions (room for neurons, bits, and axons unless a source layer is shared) filter
    them in numpy; the exact axon union is computed only for the survivors.
    """
    limits = model.chip.limits()
    n_layers = len(model.layers)
    order = sorted(range(len(slices)), key=lambda j: (-slices[j].size_key, slices[j].layer, slices[j].start))
    cores: list[PackedCore] = []
    cap = len(slices)
    room_n = np.zeros(cap, np.int64)
    room_b = np.zeros(cap, np.int64)
    room_a = np.zeros(cap, np.int64)
    has_layer = np.zeros((cap, n_layers), bool)
    fed_by = np.zeros((cap, n_layers), bool)
    cores_fed_by: dict[int, list[int]] = {}
    for j in order:
        sl = slices[j]
        n_open = len(cores)
        src = sorted(sl.sources)
        cand = np.arange(max(0, n_open - PACK_WINDOW), n_open, dtype=np.int64)
        if n_open > PACK_WINDOW:
            shared = [np.asarray(cores_fed_by[s_], np.int64) for s_ in src if s_ in cores_fed_by]
            shared = np.concatenate(shared) if shared else np.zeros(0, np.int64)
            shared = shared[(shared < n_open - PACK_WINDOW) & ~has_layer[shared, sl.layer]]
            if shared.size:
                cand = np.concatenate([np.unique(shared), cand])
        ok = ((room_n[cand] >= sl.neurons) & (room_b[cand] >= sl.bits) & ~has_layer[cand, sl.layer]
              & ((room_a[cand] >= sl.n_axons) | fed_by[cand][:, src].any(axis=1)))
        chosen = None
        for c in cand[ok].tolist():
            core = cores[c]
            if (len(core.vth | sl.vth) > limits["vth_profiles"] or len(core.cx | sl.cx) > limits["compartment_profiles"]
                    or len(core.vlim | sl.vlim) > limits["voltage_limits"]):
                continue
            union = np.union1d(core.axons(model), _slice_axons(model, sl)).size
            if union <= limits["input_axons"]:
                chosen, new_axons = c, union
                break
        if chosen is None:
            cores.append(PackedCore())
            chosen, new_axons = len(cores) - 1, sl.n_axons
            room_n[chosen], room_b[chosen] = limits["neurons"], limits["synapse_bits"]
        core = cores[chosen]
        core.slices.append(sl)
        core.vth |= sl.vth
        core.cx |= sl.cx
        core.vlim |= sl.vlim
        room_n[chosen] -= sl.neurons
        room_b[chosen] -= sl.bits
        room_a[chosen] = limits["input_axons"] - new_axons
        has_layer[chosen, sl.layer] = True
        for s_ in src:
            if not fed_by[chosen, s_]:
                fed_by[chosen, s_] = True
                cores_fed_by.setdefault(s_, []).append(chosen)
    return cores


def assignment(model: NetworkModel, cores: list[list[tuple[int, int, int]]]) -> dict[int, np.ndarray]:
    """Layer index -> the core of each of its neurons, from cores given as (layer, start, stop) slices."""
    core_of = {i: np.full(model.layers[i].n, -1, np.int64) for i in range(1, len(model.layers))}
    for c, slices in enumerate(cores):
        for i, a, z in slices:
            core_of[i][a:z] = c
    return core_of


def in_network_order(cores: list[list[tuple[int, int, int]]]) -> list[list[tuple[int, int, int]]]:
    """Cores renumbered by their first slice in network order (neighbouring layers on nearby cores)."""
    cores = [sorted(c) for c in cores if c]
    return sorted(cores, key=lambda c: c[0])
