"""The model of what each population needs: a LoihiNetwork as projections, checked against the chip.

A projection is the synapses from layer ``src`` into layer ``dst`` with one synapse format: its
nonzero weights (or all of them, ``full``) and bits per synapse = weight bits + delay bits of its
largest delay. A weight matrix with per-synapse exponents is one projection per exponent (each
exponent is its own synapse format, so its synapses sit in their own lists behind their own axons).
Each non-input neuron also carries three profile keys: its threshold profile (vThMant), its
compartment profile (iDecay, vDecay, refDelay) and its voltage-limit setting (vmin, vmax); a core
holds a limited number of distinct keys of each kind.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.loihi.mapping.kernels import transpose_indices
from snncc.targets.loihi.network import LAYER_KINDS, LoihiNetwork
from snncc.targets.loihi.mapping.resources import ChipSpec, check_delay, delay_bits


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
    if not hasattr(weight, "tocsr"):
        return _dense_pattern(np.asarray(weight), shape)
    csr = sp.csr_matrix(weight, copy=True)
    csr.eliminate_zeros()
    csr.sort_indices()
    if csr.nnz == shape[0] * shape[1]:
        return True, None
    return False, csr


PATTERN_BLOCK = 1 << 20     # entries of a dense matrix scanned at a time for its nonzero pattern


def _dense_pattern(w: np.ndarray, shape: tuple[int, int]):
    """(full, csr) of a dense matrix: only where its synapses are (the mapper reads the pattern, not the
    values: the csr holds ones), found in blocks of rows, with no coordinate or value copy of the whole."""
    import scipy.sparse as sp

    rows = max(1, PATTERN_BLOCK // max(1, shape[1]))
    counts = np.zeros(shape[0], np.int64)
    columns = []
    for r0 in range(0, shape[0], rows):
        present = w[r0:r0 + rows] != 0
        counts[r0:r0 + present.shape[0]] = present.sum(axis=1)
        columns.append(np.nonzero(present)[1].astype(np.int32))    # row by row, columns ascending
    nnz = int(counts.sum())
    if nnz == shape[0] * shape[1]:
        return True, None
    indptr = np.concatenate([[0], np.cumsum(counts)])
    indices = np.concatenate(columns) if columns else np.zeros(0, np.int32)
    csr = sp.csr_matrix((np.ones(nnz, np.int8), indices, indptr), shape=shape)
    csr.has_sorted_indices = True
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
