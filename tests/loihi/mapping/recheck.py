"""An independent re-check of a core map: per-core usage recomputed from the network and the map's
neuron ranges alone (plain loops, none of the mapper's code), compared with the limits."""

from __future__ import annotations

import math

import numpy as np


def chunk_bits(n: int, bits_per_synapse: int, per_chunk: int = 64, header: int = 10, word: int = 64) -> int:
    total = 0
    while n > 0:
        c = min(n, per_chunk)
        total += -(-(c * bits_per_synapse + header) // word) * word
        n -= c
    return total


def list_bits(nnz: int, n_range: int, bits_per_weight: int, chip) -> int:
    """Cheaper of dense (all n_range slots) and sparse (nnz synapses with an index) encodings."""
    if nnz == 0:
        return 0
    kw = dict(per_chunk=chip.synapses_per_chunk, header=chip.chunk_header_bits, word=chip.word_bits)
    dense = chunk_bits(n_range, bits_per_weight, **kw)
    if nnz >= n_range:
        return dense
    idx = min(chip.max_index_bits, max(chip.min_index_bits, math.ceil(math.log2(max(n_range, 1)))))
    return min(dense, chunk_bits(nnz, bits_per_weight + idx, **kw))


def _dense(w):
    return np.asarray(w.toarray() if hasattr(w, "toarray") else w)


def _bpw(delay, w, chip) -> int:
    d = np.asarray(delay)
    dmax = int(d.max()) if d.ndim == 0 or d.size == 1 else int(np.where(w != 0, d, 0).max())
    return chip.weight_bits + (0 if dmax <= 0 else math.ceil(math.log2(dmax + 1)))


def recompute(network, cmap: dict, chip) -> list[dict]:
    """Per-core usage recomputed from scratch; asserts every neuron is placed exactly once."""
    layers = network.layers
    offset = np.concatenate([[0], np.cumsum([lay.n for lay in layers])])
    where = {i: np.full(lay.n, -1) for i, lay in enumerate(layers) if i > 0}
    for c in cmap["cores"]:
        for s in c["layers"]:
            i = s["index"]
            assert layers[i].name == s["layer"]
            assert np.all(where[i][s["start"]:s["stop"]] == -1), "a neuron placed twice"
            where[i][s["start"]:s["stop"]] = c["core"]
    for i, w in where.items():
        assert np.all(w >= 0), f"layer {layers[i].name}: neurons left unplaced"
    projections = []     # (src layer, dst layer, dense weight, bits per weight)
    for i, lay in enumerate(layers[1:], start=1):
        w = _dense(lay.weight)
        projections.append((i - 1, i, w, _bpw(lay.delay, w, chip)))
        if lay.weight_rec is not None:
            wr = _dense(lay.weight_rec)
            projections.append((i, i, wr, _bpw(lay.delay_rec, wr, chip)))
    out = []
    n_cores = len(cmap["cores"])
    for c in range(n_cores):
        neurons = sum(int(np.count_nonzero(w == c)) for w in where.values())
        axons, bits = set(), 0
        for src, dst, w, bpw in projections:
            rows = np.flatnonzero(where[dst] == c)
            if rows.size == 0:
                continue
            nnz = np.count_nonzero(w[rows], axis=0)
            for j in np.flatnonzero(nnz):
                axons.add(int(offset[src] + j))
                bits += list_bits(int(nnz[j]), int(rows.size), bpw, chip)
        out_axons = 0
        for i, w_i in where.items():
            for j in np.flatnonzero(w_i == c):
                dests = set()
                for src, dst, w, _ in projections:
                    if src == i:
                        dests |= set(where[dst][np.flatnonzero(w[:, j])].tolist())
                out_axons += len(dests)
        vth, cx, vlim = set(), set(), set()
        for i, w_i in where.items():
            if np.any(w_i == c):
                lay = layers[i]
                vth.add(lay.v_th_mant)
                cx.add((lay.i_decay, lay.v_decay, lay.ref_delay))
                vlim.add((lay.vmin, lay.vmax))
        out.append({"core": c, "neurons": neurons, "input_axons": len(axons), "synapse_bits": bits,
                    "output_axons": out_axons, "vth_profiles": len(vth), "compartment_profiles": len(cx),
                    "voltage_limits": len(vlim)})
    return out


def assert_valid(network, cmap: dict, chip) -> list[dict]:
    """Every core within every limit (recomputed), and the map's own numbers equal the recomputation."""
    limits = {"neurons": chip.compartments_per_core, "input_axons": chip.input_axons_per_core,
              "output_axons": chip.output_axons_per_core,
              "synapse_bits": chip.synapse_words_per_core * chip.word_bits,
              "vth_profiles": chip.vth_profiles_per_core, "compartment_profiles": chip.compartment_profiles_per_core,
              "voltage_limits": chip.voltage_limits_per_core}
    usage = recompute(network, cmap, chip)
    for mine, theirs in zip(usage, cmap["cores"]):
        for k, lim in limits.items():
            assert mine[k] <= lim, f"core {mine['core']}: {k} {mine[k]} > {lim}"
            assert mine[k] == theirs[k], f"core {mine['core']}: {k} recomputed {mine[k]}, map says {theirs[k]}"
        assert theirs["chip"] == theirs["core"] // chip.cores_per_chip
    assert cmap["n_cores"] == len(cmap["cores"])
    return usage
