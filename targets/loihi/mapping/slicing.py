"""Each layer alone, cut into the fewest contiguous slices that each fit a core.

All-dense layer (every weight nonzero, one profile): a slice's usage depends only on its size m,
so with m_max the largest m that fits (compartments, synapse bits, output axons per neuron),
ceil(n / m_max) equal slices is provably the layer's minimum. Sparse layers of up to
GREEDY_MAX_NEURONS: greedy maximal slices from the front (usage only grows with a range, so this
gives the fewest contiguous slices). Larger sparse layers: the fewest equal slices, searched on
SAMPLE_SLICES evenly spaced slices (jump to k * worst ratio, then bisection), then every slice
checked and k grown until all fit. A neuron that does not fit a core alone means no map exists.

Output axons of a neuron = the destination slices it reaches (``neuron_fanout``; layers are
sliced destinations first), an upper bound since packing can only merge destinations.
"""

from __future__ import annotations

import math

import numpy as np

from snncc.targets.kit import InternalError, SnnccError
from snncc.targets.loihi.mapping.kernels import distinct_per_source
from snncc.targets.loihi.mapping.projections import NetworkModel
from snncc.targets.loihi.mapping.resources import LIMIT_TITLES, list_bits, min_bits_per_synapse
from snncc.targets.loihi.mapping.usage import RATIO_KEYS, core_usage, range_usage, worst_ratio

GREEDY_MAX_NEURONS = 20_000     # sparse layers up to this size get greedy maximal slices, larger ones equal slices
SAMPLE_SLICES = 16              # equal-slice search looks at this many slices, then checks them all


def equal_bounds(n: int, k: int) -> np.ndarray:
    """Boundaries of k contiguous slices of n neurons, sizes differing by at most one."""
    return (np.arange(k + 1, dtype=np.int64) * n) // k


def slice_ids(n: int, k: int) -> np.ndarray:
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

    def sampledworst_ratio(k):
        """Worst usage / limit over up to SAMPLE_SLICES evenly spaced slices (a guide; verified below)."""
        b = equal_bounds(n, k)
        picks = np.unique(np.linspace(0, k - 1, min(k, SAMPLE_SLICES)).round().astype(np.int64))
        worst, which = 0.0, "neurons"
        for j in picks.tolist():
            use = range_usage(model, i, int(b[j]), int(b[j + 1]))
            if out_cs is not None:
                use["output_axons"] = int(out_cs[b[j + 1]] - out_cs[b[j]])
            r, w = worst_ratio({key: np.array([v]) for key, v in use.items()}, chip,
                          RATIO_KEYS + (("output_axons",) if out_cs is not None else ()))
            if r > worst:
                worst, which = r, w
        return worst, which

    def fullworst_ratio(k):
        usage = core_usage(model, {i: slice_ids(n, k)}, k, layers={i})
        model.usage_cache[(i, k)] = usage
        r, which = worst_ratio(usage, chip)
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
            r, which = sampledworst_ratio(k)
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
        r, which = fullworst_ratio(k)           # every slice checked, not just the sample
        if r <= 1.0:
            break
        if k >= n:
            raise _fail(which, int(r * limits[which]), limits[which], lay.name, "one neuron per core")
        worst_which = which
        k = min(n, max(k + 1, math.ceil(k * r)))
        at_least = k
    else:
        raise InternalError("slicing did not converge", field=f"layer '{lay.name}'")
    why = "fits one core" if k == 1 else LIMIT_TITLES[worst_which].split(" per ")[0]
    return equal_bounds(n, k), why


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


def dense_layer_minimum(model: NetworkModel) -> dict[int, int]:
    """Each all-dense layer with one profile alone: its provable minimum of cores (output axons relaxed)."""
    return {i: len(layer_slices(model, i)[0]) - 1 for i in range(1, len(model.layers))
            if model.all_full(i) and model.uniform_profiles(i)}


def slice_layers(model: NetworkModel) -> tuple[dict[int, np.ndarray], dict[int, str]]:
    """Every non-input layer's slices, destinations first (a layer's output axons depend on how the
    layers it feeds are sliced); a recurrent layer is its own destination, so it is re-sliced until
    its own slices' output axons fit. Returns (slice boundaries, what limits them) per layer."""
    limits = model.chip.limits()
    bounds, why = {}, {}
    for i in reversed(range(1, len(model.layers))):
        fan = neuron_fanout(model, bounds, only=i)
        bounds[i], why[i] = layer_slices(model, i, fanout=fan if fan.any() else None)
        for _ in range(8):
            fan = neuron_fanout(model, bounds, only=i)
            cs = np.concatenate([[0], np.cumsum(fan)])
            b = bounds[i]
            if (cs[b[1:]] - cs[b[:-1]]).max(initial=0) <= limits["output_axons"]:
                break
            bounds[i], why[i] = layer_slices(model, i, at_least=len(b), fanout=fan)
    return bounds, why
