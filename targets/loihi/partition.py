"""Place a LoihiNetwork's neurons on cores under every per-core limit at once, using few cores.

Model of a map: every non-input layer is cut into contiguous slices; a core holds at most one
slice per layer (slices of several layers may share a core). Per core (resources.py):

    neurons        = sum of slice sizes                                    <= 1,024
    input axons    = distinct source neurons with a nonzero synapse on the core  <= 4,096
                     (one axon serves every projection from that source into the core)
    synapse bits   = sum over (source, projection) of that axon's list into the core's slice,
                     chunked (<= 64 synapses, n*b + 10 bits rounded to 64), zeros need no synapse
    output axons   = (source neuron on the core, destination core) pairs    <= 4,096
    vth / compartment profiles / voltage limits = distinct settings of the slices' neurons

Method:
  1. fan-in wider than a core's axons -> relay layer (fanin.py; changes the network, recorded).
  2. each layer alone, destinations first (a neuron's output axons = the destination slices it
     reaches): the fewest contiguous slices that each fit a core. All-dense layer: usage of a slice
     depends only on its size m, so ceil(n / m_max) equal slices is provably that layer's minimum.
     Sparse layers of up to GREEDY_MAX_NEURONS: greedy maximal slices (usage only grows with a
     range, so greedy gives the fewest contiguous slices). Larger sparse layers: the fewest equal
     slices, searched on a sample of slices, then every slice checked (grown until all fit).
  3. first-fit decreasing packing of slices onto cores (other layers' spare room); candidates are
     the last PACK_WINDOW cores plus cores sharing a source layer (plain first fit when smaller).
  4. small all-dense networks: an exact dynamic programme over "how many neurons of each layer
     on each core" (output axons relaxed) gives the minimum number of cores: a lower bound that is
     exact for the relaxed problem, and a map when it beats step 3.
  5. output-axon repair: a core over its output axons gets its source layer cut finer; repack.
  6. core ids in network order; chip = id // cores per chip. Every core is checked against every
     design rule before the map is returned.
Per-core usage is counted in one O(synapses) pass per projection (numba, _mapkernels.py).
Lower bound reported = max(total neurons / 1,024, synapse bits at the best possible chunk fill /
core memory, profiles / per-core profiles, each all-dense layer's own minimum, the exact programme
when run). It ignores axon limits for sparse layers, so it is weak for randomly connected ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from snncc.errors import SnnccError
from snncc.targets.loihi._mapkernels import distinct_per_source, pair_usage, transpose_indices
from snncc.targets.loihi.coremap import CoreMap, CoreRecord, LayerSlice
from snncc.targets.loihi.fanin import split_wide_fan_in
from snncc.targets.loihi.network import LAYER_KINDS, LoihiNetwork
from snncc.targets.loihi.resources import (
    LIMIT_TITLES,
    LOIHI1,
    ChipSpec,
    axon_list_bits,
    check_core,
    check_core_count,
    check_delay,
    delay_bits,
    list_bits,
    min_bits_per_synapse,
)

DP_MAX_STATES = 400_000
DP_MAX_WORK = 4e8
MAX_REPAIRS = 64
GREEDY_MAX_NEURONS = 20_000     # sparse layers up to this size get greedy maximal slices, larger ones equal slices
PACK_WINDOW = 512               # packing looks back this many cores (plus cores sharing a source layer)
SAMPLE_SLICES = 16              # equal-slice search looks at this many slices, then checks them all
RATIO_KEYS = ("neurons", "input_axons", "synapse_bits", "vth_profiles", "compartment_profiles", "voltage_limits")


# -- the network as projections --------------------------------------------------------------------
@dataclass
class Projection:
    """Synapses from layer ``src`` into layer ``dst``: nonzero entries only, unless ``full``.

    Sparse projections keep the index arrays twice (int32): by destination row (CSR: ``indptr``,
    ``indices`` = source of each synapse) and by source column (CSC: ``cptr``, ``cidx`` =
    destination of each synapse), so that per-core counts need no sort.
    """

    name: str
    src: int
    dst: int
    n_pre: int
    n_post: int
    bits_per_weight: int
    full: bool                        # every weight nonzero: pairs are implied, not stored
    indptr: np.ndarray | None = None
    indices: np.ndarray | None = None
    cptr: np.ndarray | None = None
    cidx: np.ndarray | None = None

    @property
    def nnz(self) -> int:
        return self.n_pre * self.n_post if self.full else int(self.indices.size)

    @property
    def post(self) -> np.ndarray:
        return np.repeat(np.arange(self.n_post, dtype=np.int64), np.diff(self.indptr))

    @property
    def pre(self) -> np.ndarray:
        return self.indices.astype(np.int64)


def _nonzeros(weight, shape: tuple[int, int], where: str):
    """(full, csr) of a dense ndarray or a scipy.sparse matrix (explicit zeros dropped), shape checked."""
    import scipy.sparse as sp

    if tuple(weight.shape) != shape:
        raise SnnccError(f"weight shape {tuple(weight.shape)} does not match {shape}", field=where)
    if sp.issparse(weight) and weight.format == "csr" and weight.has_sorted_indices and (
            weight.data.size == 0 or np.all(weight.data != 0)):
        csr = weight                     # already canonical: use its index arrays without a copy
        if csr.nnz == shape[0] * shape[1]:
            return True, None
        return False, csr
    if hasattr(weight, "tocsr"):
        csr = sp.csr_matrix(weight, copy=True)
    else:
        w = np.asarray(weight)
        if np.all(w != 0):
            return True, None
        csr = sp.csr_matrix(w)
    csr.eliminate_zeros()
    csr.sort_indices()
    if csr.nnz == shape[0] * shape[1]:
        return True, None
    return False, csr


def _max_delay(delay, csr) -> int:
    if hasattr(delay, "toarray"):
        delay = delay.toarray()
    d = np.asarray(delay)
    if d.ndim == 0 or d.size == 1:
        return int(d.reshape(-1)[0]) if d.size else 0
    if csr is None:
        return int(d.max()) if d.size else 0
    coo = csr.tocoo()
    return int(d[coo.row, coo.col].max()) if coo.nnz else 0


def _by_synapse_format(name: str, weight, exp):
    """A projection as one part per weight exponent: on the chip each exponent is its own synapse
    format, so synapses with different exponents sit in different synapse lists behind their own axons."""
    if np.ndim(exp) == 0:
        return [(name, weight)]
    dense = weight.toarray() if hasattr(weight, "toarray") else np.asarray(weight)
    exp = np.broadcast_to(np.asarray(exp), dense.shape)
    return [(f"{name} (wgtExp {int(e)})", np.where(exp == e, dense, 0)) for e in np.unique(exp)]


class NetworkModel:
    """Projections, global neuron ids and profile keys of a network, checked against the chip."""

    def __init__(self, network: LoihiNetwork, chip: ChipSpec):
        self.network, self.chip = network, chip
        self.layers = network.layers
        if not self.layers or self.layers[0].kind != "input":
            raise SnnccError("layer 0 must be the input layer", field="layers")
        sizes = np.array([lay.n for lay in self.layers], np.int64)
        self.offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.n_global = int(self.offset[-1])
        self.projections: list[Projection] = []
        for i, lay in enumerate(self.layers[1:], start=1):
            if lay.kind not in LAYER_KINDS[1:]:
                raise SnnccError(f"layer kind must be one of {LAYER_KINDS[1:]}", field=f"layer '{lay.name}'")
            if lay.weight is None:
                raise SnnccError("a non-input layer needs a weight matrix", field=f"layer '{lay.name}'")
            for name, src, weight, delay, exp in (
                    (f"{self.layers[i - 1].name}->{lay.name}", i - 1, lay.weight, lay.delay, lay.wgt_exp),
                    (f"{lay.name}->{lay.name} (recurrent)", i, lay.weight_rec, lay.delay_rec, lay.wgt_exp_rec)):
                if weight is None:
                    continue
                for part, w in _by_synapse_format(name, weight, exp):
                    self._add(part, src, i, w, delay)
        self.into = {i: [p for p in self.projections if p.dst == i] for i in range(1, len(self.layers))}
        self.checked: set[int] = set()
        self.usage_cache: dict = {}     # (layer, k equal slices) -> usage of each slice alone
        self._profile_keys()

    def _add(self, name, src, dst, weight, delay):
        n_post, n_pre = self.layers[dst].n, self.layers[src].n
        full, csr = _nonzeros(weight, (n_post, n_pre), f"layer '{self.layers[dst].name}'")
        dmax = _max_delay(delay, csr)
        bad = check_delay(self.layers[dst].name, dmax, self.chip)
        if bad or dmax < 0:
            v = bad[0] if bad else None
            raise SnnccError(v.message() if v else f"synaptic delay must be >= 0, got {dmax}",
                             field=f"layer '{self.layers[dst].name}'")
        bpw = self.chip.weight_bits + delay_bits(dmax)
        proj = Projection(name, src, dst, n_pre, n_post, bpw, full)
        if not full:
            proj.indptr = csr.indptr.astype(np.int64, copy=False)
            proj.indices = csr.indices.astype(np.int32, copy=False)
            proj.cptr, proj.cidx = transpose_indices(proj.indptr, proj.indices, n_pre)
        self.projections.append(proj)

    def _profile_keys(self):
        """Per-neuron ids of threshold profile, compartment profile and voltage-limit setting."""
        lays = self.layers[1:]

        def ids(columns):
            rows = [tuple(int(np.asarray(c[j]).flat[0]) for c in columns) for j in range(len(lays))]
            scalar = all(np.all(np.asarray(c[j]) == np.asarray(c[j]).flat[0]) for c in columns for j in range(len(lays)))
            if scalar:           # one setting per layer (the usual case): no per-neuron unique needed
                table = {r: k for k, r in enumerate(sorted(set(rows)))}
                return np.repeat(np.array([table[r] for r in rows], np.int64), [lay.n for lay in lays])
            table = np.stack([np.concatenate(c) for c in columns], axis=1)
            _, inv = np.unique(table, axis=0, return_inverse=True)
            return inv.reshape(-1).astype(np.int64)


        def col(attr):
            return [np.broadcast_to(np.asarray(getattr(lay, attr), np.int64), (lay.n,)) for lay in lays]

        self.vth_key = ids([col("v_th_mant")])
        self.cx_key = ids([col("i_decay"), col("v_decay"), col("ref_delay")])
        self.vlim_key = ids([col("vmin"), col("vmax")])
        self.neuron_offset = self.offset[1:] - self.offset[1]   # offsets of layers 1.. in the key arrays

    def layer_keys(self, i: int):
        a, b = self.neuron_offset[i - 1], self.neuron_offset[i - 1] + self.layers[i].n
        return self.vth_key[a:b], self.cx_key[a:b], self.vlim_key[a:b]

    def all_full(self, i: int) -> bool:
        return all(p.full for p in self.into[i])

    def uniform_profiles(self, i: int) -> bool:
        return all(np.all(k == k[0]) for k in self.layer_keys(i) if k.size)

    def src_layers(self, i: int) -> set[int]:
        return {p.src for p in self.into[i]}


# -- usage of an assignment -------------------------------------------------------------------------
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
            key = np.unique(np.concatenate([c * np.int64(model.n_global) + s_ for c, s_ in zip(cores, srcs)]))
            a_core, a_src = np.divmod(key, np.int64(model.n_global))
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


def _ratio(usage: dict[str, np.ndarray], chip: ChipSpec, keys=RATIO_KEYS) -> tuple[float, str]:
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


# -- step 2: slices of one layer --------------------------------------------------------------------
def equal_bounds(n: int, k: int) -> np.ndarray:
    """Boundaries of k contiguous slices of n neurons, sizes differing by at most one."""
    return (np.arange(k + 1, dtype=np.int64) * n) // k


def _slice_ids(n: int, k: int) -> np.ndarray:
    b = equal_bounds(n, k)
    return np.repeat(np.arange(k, dtype=np.int64), np.diff(b))


def dense_bits_curve(model: NetworkModel, i: int, m_max: int) -> np.ndarray:
    """Synapse bits of a slice of m = 0..m_max neurons of an all-dense layer (alone on a core)."""
    m = np.arange(m_max + 1, dtype=np.int64)
    bits = np.zeros(m_max + 1, np.int64)
    for p in model.into[i]:
        bits += p.n_pre * list_bits(m, p.bits_per_weight, model.chip)
    return bits


def _dense_axons(model: NetworkModel, i: int) -> int:
    return int(sum(model.layers[s].n for s in model.src_layers(i)))


def _fail(limit: str, value: int, allowed: int, layer: str, detail: str) -> SnnccError:
    return SnnccError(f"{LIMIT_TITLES[limit]}: needs {value:,}, limit {allowed:,} ({detail}); no map exists",
                      field=f"layer '{layer}'")


def _single_neuron_check(model: NetworkModel, i: int) -> None:
    """A neuron alone on a core must fit, else no map can exist: name the limit and the layer.

    Alone, each of its synapses is its own list of one: axons = its sources, bits = sum of one-synapse lists.
    """
    if i in model.checked:
        return
    chip, lay = model.chip, model.layers[i]
    limits = chip.limits()
    axons = np.zeros(lay.n, np.int64)
    bits = np.zeros(lay.n, np.int64)
    for p in model.into[i]:
        rows = np.full(lay.n, p.n_pre, np.int64) if p.full else np.diff(p.indptr)
        axons += rows
        bits += rows * int(list_bits(1, p.bits_per_weight, chip))
    for k, v in (("input_axons", axons), ("synapse_bits", bits)):
        worst = int(np.argmax(v)) if v.size else 0
        if v.size and v[worst] > limits[k]:
            raise _fail(k, int(v[worst]), limits[k], lay.name, f"neuron {worst} alone on a core")
    model.checked.add(i)


def layer_slices(model: NetworkModel, i: int, at_least: int = 1,
                 fanout: np.ndarray | None = None) -> tuple[np.ndarray, str]:
    """(slice boundaries, what limits them): the fewest contiguous slices of layer i that each fit a core alone.

    All-dense layers: ceil(n / m_max) equal slices (provably the fewest). Sparse layers up to
    GREEDY_MAX_NEURONS: greedy maximal slices (the fewest contiguous ones); larger: the fewest
    equal slices found by growth and bisection. ``at_least`` forces more slices (output-axon repair);
    ``fanout`` (output axons of each neuron, from the other layers' slicing) adds the output-axon limit.
    """
    out_cs = None if fanout is None else np.concatenate([[0], np.cumsum(fanout)]).astype(np.int64)
    chip, lay = model.chip, model.layers[i]
    limits = chip.limits()
    n = lay.n
    if model.all_full(i) and model.uniform_profiles(i):
        axons = _dense_axons(model, i)
        if axons > limits["input_axons"]:
            raise _fail("input_axons", axons, limits["input_axons"], lay.name, "fan-in of every neuron")
        cap = min(n, chip.compartments_per_core)
        bits = dense_bits_curve(model, i, cap)
        fits = np.flatnonzero(bits[1:] <= limits["synapse_bits"]) + 1
        if fits.size == 0:
            raise _fail("synapse_bits", int(bits[1]), limits["synapse_bits"], lay.name, "one neuron alone on a core")
        m_max = int(fits.max())
        if fanout is not None and fanout.size and fanout.max() > 0:
            m_out = max(1, limits["output_axons"] // int(fanout.max()))
            if m_out < m_max:
                m_max = m_out
                why_out = f"output axons ({m_max} neurons per core)"
        if fanout is not None and fanout.size and int(fanout.max()) > limits["output_axons"]:
            raise _fail("output_axons", int(fanout.max()), limits["output_axons"], lay.name, "one neuron's destinations")
        if "why_out" in locals():
            why = why_out
        elif n <= m_max:
            why = "fits one core"
        elif m_max == chip.compartments_per_core:
            why = f"compartments ({m_max} per core)"
        else:
            why = f"synapse memory ({m_max} neurons per core, {int(bits[m_max]):,} bits)"
        return equal_bounds(n, min(n, max(at_least, -(-n // m_max)))), why
    _single_neuron_check(model, i)
    if n <= GREEDY_MAX_NEURONS:
        bounds, why = greedy_bounds(model, i, out_cs)
        if len(bounds) - 1 >= at_least:
            return bounds, why

    def sampled_ratio(k):
        """Worst usage / limit over up to SAMPLE_SLICES evenly spaced slices (a guide; verified below)."""
        b = equal_bounds(n, k)
        picks = np.unique(np.linspace(0, k - 1, min(k, SAMPLE_SLICES)).round().astype(np.int64))
        worst, which = 0.0, "neurons"
        for j in picks.tolist():
            use = range_usage(model, i, int(b[j]), int(b[j + 1]))
            if out_cs is not None:
                use["output_axons"] = int(out_cs[b[j + 1]] - out_cs[b[j]])
            r, w = _ratio({key: np.array([v]) for key, v in use.items()}, chip,
                          RATIO_KEYS + (("output_axons",) if out_cs is not None else ()))
            if r > worst:
                worst, which = r, w
        return worst, which

    def full_ratio(k):
        usage = core_usage(model, {i: _slice_ids(n, k)}, k, layers={i})
        model.usage_cache[(i, k)] = usage
        r, which = _ratio(usage, chip)
        if out_cs is not None:
            b = equal_bounds(n, k)
            r_out = float((out_cs[b[1:]] - out_cs[b[:-1]]).max()) / limits["output_axons"]
            if r_out > r:
                r, which = r_out, "output_axons"
        return r, which

    p_nnz = sum(p.nnz for p in model.into[i])
    bpw = min((p.bits_per_weight for p in model.into[i]), default=chip.weight_bits)
    k = max(at_least, -(-n // chip.compartments_per_core),
            math.ceil(p_nnz * min_bits_per_synapse(bpw, chip) / limits["synapse_bits"]))
    k = min(k, n)
    worst_which = "neurons"
    for _verify in range(32):
        lo, hi = max(at_least, k) - 1, None
        for _ in range(64):        # usage ~ 1/k: jump to k * ratio, then close the gap by bisection
            r, which = sampled_ratio(k)
            if r <= 1.0:
                hi = k
            else:
                if k >= n:
                    raise _fail(which, int(r * limits[which]), limits[which], lay.name, "one neuron per core")
                lo, worst_which = k, which
            if hi is not None and hi - lo <= 1:
                break
            guess = math.ceil(k * r)
            upper = n if hi is None else hi - 1
            nxt = min(upper, max(lo + 1, guess))
            if nxt == k or (hi is not None and not lo < nxt < hi):
                nxt = (lo + hi) // 2 if hi is not None else min(n, k + 1)
            k = nxt
        k = hi
        r, which = full_ratio(k)           # every slice checked, not just the sample
        if r <= 1.0:
            break
        if k >= n:
            raise _fail(which, int(r * limits[which]), limits[which], lay.name, "one neuron per core")
        worst_which = which
        k = min(n, max(k + 1, math.ceil(k * r)))
        at_least = k
    else:
        raise SnnccError("internal: slicing did not converge", field=f"layer '{lay.name}'")
    why = "fits one core" if k == 1 else LIMIT_TITLES[worst_which].split(" per ")[0]
    return equal_bounds(n, k), why


def range_usage(model: NetworkModel, i: int, a: int, z: int) -> dict[str, int]:
    """Usage of neurons a..z-1 of layer i alone on a core (no output axons: they depend on others)."""
    m = z - a
    axons, bits = [], 0
    for p in model.into[i]:
        if p.full:
            axons.append(np.arange(p.n_pre, dtype=np.int64) + model.offset[p.src])
            bits += p.n_pre * int(list_bits(m, p.bits_per_weight, model.chip))
            continue
        pre = p.indices[p.indptr[a]:p.indptr[z]]
        uniq, cnt = np.unique(pre, return_counts=True)
        axons.append(uniq.astype(np.int64) + model.offset[p.src])
        bits += int(pair_bits(cnt, np.full(cnt.size, m, np.int64), p.bits_per_weight, model.chip).sum())
    srcs = {p.src for p in model.into[i]}
    n_axons = sum(x.size for x in axons) if len(srcs) == len(axons) else np.unique(np.concatenate(axons)).size
    out = {"neurons": m, "input_axons": int(n_axons), "synapse_bits": int(bits)}
    for name, keys in zip(("vth_profiles", "compartment_profiles", "voltage_limits"), model.layer_keys(i)):
        k = keys[a:z]
        out[name] = 1 if k.size and k.min() == k.max() else int(np.unique(k).size)
    return out


def _range_fits(model: NetworkModel, i: int, a: int, z: int, out_cs) -> tuple[bool, str]:
    """Does neurons a..z-1 of layer i fit one core alone (compartments, axons, bits, profiles, output axons)?"""
    limits = model.chip.limits()
    if z - a > limits["neurons"]:
        return False, "neurons"
    if out_cs is not None and out_cs[z] - out_cs[a] > limits["output_axons"]:
        return False, "output_axons"
    use = range_usage(model, i, a, z)
    for k in ("synapse_bits", "input_axons", "vth_profiles", "compartment_profiles", "voltage_limits"):
        if use[k] > limits[k]:
            return False, k
    return True, ""


def greedy_bounds(model: NetworkModel, i: int, out_cs=None) -> tuple[np.ndarray, str]:
    """Maximal contiguous slices from the front: the fewest contiguous slices (usage grows with the range)."""
    n = model.layers[i].n
    bounds, a, guess, why = [0], 0, 1, "fits one core"
    while a < n:
        lo, hi = a + 1, None                         # lo fits (single-neuron check done), hi does not
        step = max(guess, 1)
        while True:
            z = min(n, a + step)
            ok, w = _range_fits(model, i, a, z, out_cs)
            if ok:
                lo = z
                if z == n:
                    break
                step *= 2
            else:
                hi, why = z, w
                break
        if hi is not None:
            while hi - lo > 1:
                mid = (lo + hi) // 2
                ok, w = _range_fits(model, i, a, mid, out_cs)
                if ok:
                    lo = mid
                else:
                    hi, why = mid, w
        bounds.append(lo)
        guess, a = lo - a, lo
    why = "fits one core" if len(bounds) == 2 else LIMIT_TITLES[why].split(" per ")[0]
    return np.array(bounds, np.int64), why


# -- step 3: packing --------------------------------------------------------------------------------
@dataclass
class _Slice:
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


def _slice_axons(model: NetworkModel, sl: _Slice) -> np.ndarray:
    """Sorted global ids of the sources with a nonzero synapse onto the slice."""
    parts = []
    for p in model.into[sl.layer]:
        if p.full:
            parts.append(np.arange(p.n_pre, dtype=np.int64) + model.offset[p.src])
        else:
            parts.append(p.indices[p.indptr[sl.start]:p.indptr[sl.stop]].astype(np.int64) + model.offset[p.src])
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)


def _make_slices(model: NetworkModel, bounds: dict[int, np.ndarray]) -> list[_Slice]:
    chip = model.chip
    limits = chip.limits()
    out: list[_Slice] = []
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
            sl = _Slice(i, a, z, z - a, int(usage["synapse_bits"][s]), int(usage["input_axons"][s]), sources,
                        frozenset(np.unique(vth[a:z]).tolist()), frozenset(np.unique(cx[a:z]).tolist()),
                        frozenset(np.unique(vlim[a:z]).tolist()))
            sl.size_key = max(sl.neurons / limits["neurons"], sl.bits / limits["synapse_bits"],
                              sl.n_axons / limits["input_axons"])
            out.append(sl)
    return out


class _Core:
    def __init__(self):
        self.slices: list[_Slice] = []
        self.vth, self.cx, self.vlim = set(), set(), set()

    def axons(self, model: NetworkModel) -> np.ndarray:
        return np.unique(np.concatenate([_slice_axons(model, s) for s in self.slices]))


def pack(model: NetworkModel, slices: list[_Slice]) -> list[_Core]:
    """First-fit decreasing: each slice (largest first) onto the first open core it fits, else a new core.

    Candidates: the last PACK_WINDOW cores opened plus every core fed by one of the slice's source
    layers (for networks of up to PACK_WINDOW cores this is plain first fit over all cores). Cheap
    necessary conditions (room for neurons, bits, and axons unless a source layer is shared) filter
    them in numpy; the exact axon union is computed only for the survivors.
    """
    limits = model.chip.limits()
    n_layers = len(model.layers)
    order = sorted(range(len(slices)), key=lambda j: (-slices[j].size_key, slices[j].layer, slices[j].start))
    cores: list[_Core] = []
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
            cores.append(_Core())
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


def _assignment(model: NetworkModel, cores: list[list[tuple[int, int, int]]]) -> dict[int, np.ndarray]:
    core_of = {i: np.full(model.layers[i].n, -1, np.int64) for i in range(1, len(model.layers))}
    for c, slices in enumerate(cores):
        for i, a, z in slices:
            core_of[i][a:z] = c
    return core_of


def _in_network_order(cores: list[list[tuple[int, int, int]]]) -> list[list[tuple[int, int, int]]]:
    """Cores renumbered by their first slice in network order (neighbouring layers on nearby cores)."""
    cores = [sorted(c) for c in cores if c]
    return sorted(cores, key=lambda c: c[0])


# -- step 4: the exact programme for small dense networks -------------------------------------------
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


def _dp_cores(model: NetworkModel, configs) -> list[list[tuple[int, int, int]]]:
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


# -- lower bound -----------------------------------------------------------------------------------
def lower_bound(model: NetworkModel, layer_minimum: dict[int, int], dp: int | None) -> tuple[int, str]:
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


# -- the whole pass ---------------------------------------------------------------------------------
def neuron_fanout(model: NetworkModel, bounds: dict[int, np.ndarray], only: int) -> np.ndarray:
    """Output axons each neuron of layer ``only`` needs: the destination slices (already sliced
    layers only) it has synapses into. Slices are taken as cores; packing can only merge
    destinations, so this is an upper bound."""
    out = {only: np.zeros(model.layers[only].n, np.int64)}
    for p in model.projections:
        if p.src != only or p.dst not in bounds:
            continue
        k_dst = len(bounds[p.dst]) - 1
        if p.full:
            out[p.src] += k_dst
            continue
        if p.nnz == 0:
            continue
        slice_of = np.repeat(np.arange(k_dst, dtype=np.int64), np.diff(bounds[p.dst]))
        out[p.src] += distinct_per_source(p.cptr, p.cidx, slice_of)
    return out[only]


def map_network(network: LoihiNetwork, chip: ChipSpec = LOIHI1) -> CoreMap:
    """Place every non-input layer on cores under all of ``chip``'s limits; deterministic.

    Returns a ``CoreMap`` whose ``network`` is the network actually mapped (with fan-in relays when
    a layer's fan-in exceeds a core's input axons; see ``transforms``). Raises ``SnnccError`` naming
    the limit and the layer when no map can exist.
    """
    mapped, transforms = split_wide_fan_in(network, chip)
    model = NetworkModel(mapped, chip)
    idx = list(range(1, len(model.layers)))
    limits = chip.limits()
    layer_minimum = {}
    for i in idx:              # each all-dense layer alone: its provable minimum (output axons relaxed)
        if model.all_full(i) and model.uniform_profiles(i):
            layer_minimum[i] = len(layer_slices(model, i)[0]) - 1
    bounds, why = {}, {}
    for i in reversed(idx):    # destinations first: a layer's output axons depend on their slicing
        fan = neuron_fanout(model, bounds, only=i)
        bounds[i], why[i] = layer_slices(model, i, fanout=fan if fan.any() else None)
        for _ in range(8):     # a recurrent layer is its own destination
            fan = neuron_fanout(model, bounds, only=i)
            cs = np.concatenate([[0], np.cumsum(fan)])
            b = bounds[i]
            if (cs[b[1:]] - cs[b[:-1]]).max(initial=0) <= limits["output_axons"]:
                break
            bounds[i], why[i] = layer_slices(model, i, at_least=len(b), fanout=fan)
    dp = dp_min_cores(model)
    dp_k = dp[0] if dp else None
    lb, lb_method = lower_bound(model, layer_minimum, dp_k)
    forced = dict(bounds)
    method = ("per-layer fewest slices (dense: ceil(n / m_max); sparse: greedy maximal or equal) + "
              "first-fit-decreasing packing" + (" + exact count search" if dp else "") + " + output-axon repair")
    for _ in range(MAX_REPAIRS):
        packed = pack(model, _make_slices(model, forced))
        cores = _in_network_order([[(q.layer, q.start, q.stop) for q in c.slices] for c in packed])
        if dp and dp[0] < len(cores):
            dp_layout = _in_network_order(_dp_cores(model, dp[1]))
            usage = core_usage(model, _assignment(model, dp_layout), len(dp_layout))
            if _ratio(usage, chip, RATIO_KEYS + ("output_axons",))[0] <= 1.0:
                cores = dp_layout
        core_of = _assignment(model, cores)
        usage = core_usage(model, core_of, len(cores))
        over = np.flatnonzero(usage["output_axons"] > limits["output_axons"])
        if over.size == 0:
            break
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
    else:
        raise SnnccError(f"{LIMIT_TITLES['output_axons']}: still exceeded after {MAX_REPAIRS} repairs",
                         field="core map")
    bad = check_core_count(len(cores), chip)
    if bad:
        raise SnnccError(bad[0].message() + "; no map exists", field="network")
    records = []
    for c, slices in enumerate(cores):
        records.append(CoreRecord(
            core=c, chip=c // chip.cores_per_chip,
            layers=[LayerSlice(model.layers[i].name, i, a, z) for i, a, z in slices],
            **{k: int(usage[k][c]) for k in ("neurons", "input_axons", "output_axons", "synapse_bits",
                                             "vth_profiles", "compartment_profiles", "voltage_limits")}))
    for rec in records:           # the map is checked against every design rule before it is returned
        v = check_core({**rec.usage(), "core": rec.core, "layers": [{"layer": s.layer} for s in rec.layers]}, chip)
        if v:
            raise SnnccError(v[0].message() + " (internal: the partitioner produced an invalid map)", field="core map")
    if lb > len(records):
        raise SnnccError(f"internal: lower bound {lb} above the map's {len(records)} cores", field="core map")
    return CoreMap(
        chip=chip, cores=records, lower_bound=lb, lower_bound_method=lb_method, method=method,
        layer_limits={model.layers[i].name: f"{len(forced[i]) - 1} slice(s); {why[i]}" for i in idx},
        transforms=transforms,
        network_layers=[{"index": j, "name": lay.name, "kind": lay.kind, "n": lay.n} for j, lay in enumerate(model.layers)],
        network=mapped)
