"""A Xylo spec as an IR graph: the chip's order and delays with its decays read as 1 - 2^-dash.

The float twin of a spec dict (``lower.py``'s contract) says what the network spec means in the IR's
terms; it equals the chip except for the chip's integer rounding of decays (x >> d rounds toward
-inf, and a non-zero state decays by at least 1) and its 16-bit saturation:

    hidden neuron j, synapse k:  I_k <- a_k I_k + a_k (w_in[:, j, k] . x[t] + w_rec[:, j, k] . s[t-1])
                                 a_k = 1 - 2^-dash_syn(_2)[j],  w = int8 weight << weight_shift
    hidden readout:              V <- b V + I_1 + I_2 + bias,   b = 1 - 2^-dash_mem[j]
                                 s = min(31, floor(V / threshold)) on V >= threshold;  V -= s * threshold
    output neuron o:             J <- a J + a (w_out[:, o] . s[t-1]);  U <- b U + J + bias_out
                                 one spike on U >= threshold_out;  U -= threshold_out

As IR nodes: per synapse k an integrator LIF ``syn{k}`` (threshold +inf, beta 0, so its voltage is
its current) fed by ``w_in{k}`` (delay 0) and ``w_rec{k}`` (delay 1), both feeding the readout LIF
``hidden`` (alpha 0) through identity Dense nodes on their voltage ports; ``hidden`` -> ``w_out``
(delay 1) -> ``output`` (LIF) -> Readout(spike_count) -> Output. Discretisation "euler" with
tau = dt / (1 - a) states every decay exactly. A hidden neuron whose threshold exceeds half the
16-bit range fires at most once per step on the chip (V <= 32767 < 2 * threshold); the twin states
that as ``max_spikes`` 1 for the whole population when every threshold does, else 31.
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense, Input, Output, Readout
from snncc.targets.xylo.chip import CORE

STATE_MAX = CORE.state_max

HIDDEN_CAP = 31
OUTPUT_CAP = 1


def _taus(dt: float, dash: np.ndarray) -> np.ndarray:
    """Euler tau giving decay 1 - 2^-dash exactly (tau = dt for dash 0: decay 0)."""
    return dt * np.power(2.0, np.asarray(dash, np.float64))


def shifted(weights, shift: int) -> np.ndarray:
    """int8 weights as the chip delivers them (<< shift, narrowed to int16), in float64. Float weights
    (a provisional spec before rounding) are scaled by 2^shift and never wrap."""
    arr = np.asarray(weights)
    if np.issubdtype(arr.dtype, np.floating):
        return arr.astype(np.float64) * 2.0 ** int(shift)
    w = arr.astype(np.int64) << int(shift)
    return ((w + 2 ** 15) % 2 ** 16 - 2 ** 15).astype(np.float64)


def spec_graph(spec: dict, dt: float, name: str = "xylo-twin") -> Graph:
    """The IR graph of ``spec`` (see the module docstring). Aliases are refused (the IR has no spike copy)."""
    if any(len(a) for a in (spec.get("aliases") or [])):
        raise SnnccError("the IR twin of a spec does not state aliases", field="aliases")
    w_in = np.asarray(spec["weights_in"])
    w_in = w_in[:, :, None] if w_in.ndim == 2 else w_in
    n_in, n_ien, syn = w_in.shape
    th = np.asarray(spec["threshold"], np.float64)
    n = th.size
    w_rec = np.asarray(spec.get("weights_rec") if spec.get("weights_rec") is not None else np.zeros((n, n), np.int8))
    w_rec = w_rec[:, :, None] if w_rec.ndim == 2 else w_rec
    syn = max(syn, w_rec.shape[2])
    w_out = np.asarray(spec["weights_out"])
    n_out = w_out.shape[1]
    dashes = [np.asarray(spec["dash_syn"]), np.asarray(spec.get("dash_syn_2", spec["dash_syn"]))][:syn]
    g = Graph(dt, name=name, metadata={"xylo_twin": True})
    g.add("input", Input(n_in))
    g.add("hidden", LIF(n, tau_syn=dt, tau_mem=_taus(dt, spec["dash_mem"]), threshold=th, reset="subtract",
                        discretisation="euler", bias=np.asarray(spec.get("bias", np.zeros(n)), np.float64),
                        bias_placement="voltage", fire_test=">=",
                        max_spikes=OUTPUT_CAP if np.all(2 * th > STATE_MAX) else HIDDEN_CAP))
    for k in range(syn):
        a = 1.0 - np.power(2.0, -dashes[k].astype(np.float64))
        g.add(f"syn{k}", LIF(n, tau_syn=_taus(dt, dashes[k]), tau_mem=dt, threshold=np.inf, reset="subtract",
                             discretisation="euler"))
        full_in = np.zeros((n, n_in))
        if k < w_in.shape[2]:
            full_in[:n_ien] = shifted(w_in[:, :, k], spec.get("weight_shift_in", 0)).T
        g.add(f"w_in{k}", Dense(a[:, None] * full_in))
        g.connect("input", f"w_in{k}")
        g.connect(f"w_in{k}", f"syn{k}")
        if k < w_rec.shape[2] and np.any(w_rec[:, :, k]):
            g.add(f"w_rec{k}", Dense(a[:, None] * shifted(w_rec[:, :, k], spec.get("weight_shift_rec", 0)).T))
            g.connect("hidden", f"w_rec{k}", delay=1)
            g.connect(f"w_rec{k}", f"syn{k}")
        g.add(f"sum{k}", Dense(np.eye(n)))
        g.connect(f"syn{k}", f"sum{k}", port="voltage")
        g.connect(f"sum{k}", "hidden")
    a_o = 1.0 - np.power(2.0, -np.asarray(spec["dash_syn_out"], np.float64))
    full_out = np.zeros((n, n_out))
    full_out[n - w_out.shape[0]:] = shifted(w_out, spec.get("weight_shift_out", 0))   # from the last N_oen
    g.add("w_out", Dense(a_o[:, None] * full_out.T))
    g.add("output", LIF(n_out, tau_syn=_taus(dt, spec["dash_syn_out"]), tau_mem=_taus(dt, spec["dash_mem_out"]),
                        threshold=np.asarray(spec["threshold_out"], np.float64), reset="subtract",
                        discretisation="euler", bias=np.asarray(spec.get("bias_out", np.zeros(n_out)), np.float64),
                        bias_placement="voltage", fire_test=">=", max_spikes=OUTPUT_CAP))
    g.add("readout", Readout(n_out, mode="spike_count"))
    g.add("out", Output(n_out))
    g.connect("hidden", "w_out", delay=1)
    g.connect("w_out", "output")
    g.connect("output", "readout")
    g.connect("readout", "out")
    return g
