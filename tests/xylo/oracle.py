"""The vendor's simulator as the oracle: an ``XyloSpec`` run in ``xylosim.v2.XyloLayer`` directly.

xylosim 0.1.3's Python binding (pybind11, ``src/v2/cpp/v2.cpp``):

* ``XyloSynapse(target_neuron_id, target_synapse_id, weight)``: one synapse, weight int8;
* ``XyloLayer(synapses_in, synapses_rec, synapses_out, aliases, threshold, threshold_out,
  has_bias, bias, bias_out, weight_shift_inp, weight_shift_rec, weight_shift_out, dash_mem,
  dash_mem_out, dash_syns, dash_syns_out, name)``: ``synapses_*[pre]`` lists the synapses of
  pre-synaptic neuron ``pre`` (the layer keeps raw pointers to them: the Python objects must stay
  alive as long as the layer); ``dash_syns[k]`` lists one dash per synaptic current of hidden
  neuron k (two here, as Rockpool builds them), ``dash_syns_out[m]`` one per output neuron;
* ``layer.evolve(raster)`` takes a (T, Nin) list of lists of event counts (0 .. 255) and
  returns the (T, Nout) output counts; it continues from the current state, so every sample
  here starts with ``layer.reset_all()``; afterwards ``rec_v_mem``, ``rec_i_syn``,
  ``rec_i_syn2`` (N lists of T values), ``rec_recurrent_spikes`` (T lists of N), ``rec_v_mem_out``
  and ``rec_i_syn_out`` hold the run's states.

The synapse lists are built the way Rockpool's ``from_specification`` builds them: the output
weights' rows belong to the LAST N_oen hidden neurons, ``has_bias`` is set when any bias is
non-zero. This module is written for snncc's tests; it copies nothing from Rockpool.
"""

from __future__ import annotations

import numpy as np

from snncc.targets.xylo.emulation.emulator import XyloResult
from snncc.targets.xylo.spec import XyloSpec


class XyloSimOracle:
    """One ``XyloLayer`` built from a spec, run sample by sample."""

    def __init__(self, spec: XyloSpec):
        from xylosim.v2 import XyloLayer, XyloSynapse

        self.spec = spec

        def synapse_lists(w: np.ndarray, first_pre: int = 0, n_pre: int | None = None):
            w = w if w.ndim == 3 else w[:, :, None]
            lists = [[] for _ in range(first_pre)]
            for pre in range(w.shape[0]):
                lists.append([XyloSynapse(int(post), int(syn), int(w[pre, post, syn]))
                              for syn in range(w.shape[2]) for post in np.flatnonzero(w[pre, :, syn])])
            return lists

        n = spec.n_hidden
        self._synapses = (synapse_lists(spec.weights_in), synapse_lists(spec.weights_rec),
                          synapse_lists(spec.weights_out, first_pre=n - spec.n_oen))
        ints = lambda a: [int(x) for x in a]   # noqa: E731
        self.layer = XyloLayer(
            synapses_in=self._synapses[0], synapses_rec=self._synapses[1], synapses_out=self._synapses[2],
            aliases=[list(a) for a in spec.aliases],
            threshold=ints(spec.threshold), threshold_out=ints(spec.threshold_out),
            has_bias=bool(np.any(spec.bias != 0) or np.any(spec.bias_out != 0)),
            bias=ints(spec.bias), bias_out=ints(spec.bias_out),
            weight_shift_inp=spec.weight_shift_in, weight_shift_rec=spec.weight_shift_rec,
            weight_shift_out=spec.weight_shift_out,
            dash_mem=ints(spec.dash_mem), dash_mem_out=ints(spec.dash_mem_out),
            dash_syns=[[int(a), int(b)] for a, b in zip(spec.dash_syn, spec.dash_syn_2)],
            dash_syns_out=[[int(d)] for d in spec.dash_syn_out], name="snncc-oracle")

    def run_one(self, x: np.ndarray) -> np.ndarray:
        """(T, Nin) counts -> (T, Nout) output counts, from zero state."""
        self.layer.reset_all()
        return np.asarray(self.layer.evolve(np.asarray(x, np.int64).tolist()), np.uint8).reshape(len(x), -1)

    def run(self, inputs: np.ndarray, *, record: bool = False) -> XyloResult:
        """(B, T, Nin) counts -> the same record as snncc's emulator."""
        inputs = np.asarray(inputs)
        b, t = inputs.shape[:2]
        n, n_out = self.spec.n_hidden, self.spec.n_out
        out = np.zeros((b, t, n_out), np.uint8)
        rec = {k: [] for k in ("vmem", "isyn", "isyn2", "spikes", "vmem_out", "isyn_out")}
        for i in range(b):
            out[i] = self.run_one(inputs[i])
            if record:
                L = self.layer
                rec["vmem"].append(np.asarray(L.rec_v_mem, np.int16).reshape(n, t).T)
                rec["isyn"].append(np.asarray(L.rec_i_syn, np.int16).reshape(n, t).T)
                rec["isyn2"].append(np.asarray(L.rec_i_syn2, np.int16).reshape(n, t).T)
                rec["spikes"].append(np.asarray(L.rec_recurrent_spikes, np.uint8).reshape(t, n))
                rec["vmem_out"].append(np.asarray(L.rec_v_mem_out, np.int16).reshape(n_out, t).T)
                rec["isyn_out"].append(np.asarray(L.rec_i_syn_out, np.int16).reshape(n_out, t).T)
        if not record:
            return XyloResult(out)
        return XyloResult(out, **{k: np.stack(v) for k, v in rec.items()})
