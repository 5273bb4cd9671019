"""Run a Xylo spec dict (the keyword arguments of XyloSim.from_specification) in the vendor's
simulator, ``xylosim.v2`` (Xylo Audio 2's core), driven directly through its Python binding.

Test and bench helper only: xylosim is the oracle, never a dependency of the snncc package.
Conventions (those of Rockpool's ``from_specification``): ``weights_in`` (Nin, N[, 2]) and
``weights_rec`` (N, N[, 2]) with the last axis the synapse; ``weights_out`` (N_oen, Nout) from the
LAST N_oen hidden neurons; every hidden neuron has two synaptic currents (``dash_syn``,
``dash_syn_2``), every output neuron one; biases are enabled when any bias is non-zero.
"""

from __future__ import annotations

import numpy as np


def _synapses(weights: np.ndarray, skip: int = 0):
    from xylosim.v2 import XyloSynapse

    w = np.asarray(weights)
    if w.ndim == 2:
        w = w[:, :, None]
    rows = [[] for _ in range(skip)]
    for pre in range(w.shape[0]):
        row = []
        for syn in range(w.shape[2]):
            for post in np.flatnonzero(w[pre, :, syn]):
                row.append(XyloSynapse(int(post), int(syn), int(w[pre, post, syn])))
        rows.append(row)
    return rows


class _Layer:
    """A XyloLayer and the synapse objects it points to (the C++ keeps raw pointers: they must live)."""

    def __init__(self, layer, synapses):
        self.layer, self.synapses = layer, synapses

    def __getattr__(self, name):
        return getattr(self.layer, name)


def build_layer(spec: dict) -> _Layer:
    """A ``xylosim.v2.XyloLayer`` holding ``spec`` (wrapped with the synapses it points to)."""
    from xylosim.v2 import XyloLayer

    n = len(spec["threshold"])
    n_out = len(spec["threshold_out"])
    w_rec = spec.get("weights_rec")
    if w_rec is None:
        w_rec = np.zeros((n, n), np.int8)
    w_out = np.asarray(spec["weights_out"])
    bias = np.asarray(spec.get("bias", np.zeros(n)), np.int64)
    bias_out = np.asarray(spec.get("bias_out", np.zeros(n_out)), np.int64)
    aliases = spec.get("aliases") or [[] for _ in range(n)]
    syn = (_synapses(spec["weights_in"]), _synapses(w_rec), _synapses(w_out, skip=n - w_out.shape[0]))
    return _Layer(XyloLayer(
        synapses_in=syn[0],
        synapses_rec=syn[1],
        synapses_out=syn[2],
        aliases=[[int(a) for a in row] for row in aliases],
        threshold=[int(v) for v in spec["threshold"]],
        threshold_out=[int(v) for v in spec["threshold_out"]],
        has_bias=bool(np.any(bias != 0) or np.any(bias_out != 0)),
        bias=[int(v) for v in bias], bias_out=[int(v) for v in bias_out],
        weight_shift_inp=int(spec.get("weight_shift_in", 0)),
        weight_shift_rec=int(spec.get("weight_shift_rec", 0)),
        weight_shift_out=int(spec.get("weight_shift_out", 0)),
        dash_mem=[int(v) for v in spec["dash_mem"]],
        dash_mem_out=[int(v) for v in spec["dash_mem_out"]],
        dash_syns=[[int(a), int(b)] for a, b in zip(spec["dash_syn"], spec.get("dash_syn_2", spec["dash_syn"]))],
        dash_syns_out=[[int(v)] for v in spec["dash_syn_out"]],
        name="snncc-oracle",
    ), syn)


def run(spec: dict, x: np.ndarray, record: bool = False, layer=None) -> dict[str, np.ndarray]:
    """Run every sample of ``x`` (B, T, Nin) spike counts from a reset state.

    Returns ``output`` (B, T, Nout) and ``hidden`` (B, T, N) spike counts; with ``record`` also
    ``vmem``, ``isyn``, ``isyn2`` (B, T, N), ``vmem_out``, ``isyn_out`` (B, T, Nout).
    """
    x = np.asarray(x)
    if x.ndim == 2:
        x = x[None]
    layer = layer or build_layer(spec)
    keys = ("output", "hidden") + (("vmem", "isyn", "isyn2", "vmem_out", "isyn_out") if record else ())
    out: dict[str, list] = {k: [] for k in keys}
    for sample in x:
        layer.reset_all()
        out["output"].append(np.asarray(layer.evolve(sample.astype(np.int64).tolist()), np.int16))
        out["hidden"].append(np.asarray(layer.rec_recurrent_spikes, np.int16))
        if record:
            out["vmem"].append(np.asarray(layer.rec_v_mem, np.int32).T)
            out["isyn"].append(np.asarray(layer.rec_i_syn, np.int32).T)
            isyn2 = [list(v) for v in layer.rec_i_syn2]
            out["isyn2"].append(np.asarray(isyn2, np.int32).T)
            out["vmem_out"].append(np.asarray(layer.rec_v_mem_out, np.int32).T)
            out["isyn_out"].append(np.asarray(layer.rec_i_syn_out, np.int32).T)
    return {k: np.stack(v) for k, v in out.items()}
