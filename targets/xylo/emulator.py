"""Bit-exact emulation of the Xylo v2 SNN core, as xylosim 0.1.3 computes it (docs/xylo.md).

One time step t, all integers, sat(x) = min(max(x, -32768), 32767), wrap(x) = x narrowed to int16:

1. input events of step t, channel j = 0 .. Nin-1 in order, c = min(x[t, j], 15) events each:
   for every input expansion neuron k < N_ien and synapse s:  Isyn_s[k] = sat(Isyn_s[k] + c * w)
   with w = wrap(weights_in[j, k, s] << weight_shift_in)  (c saturating additions of one weight,
   all of one sign, equal this single one);
2. hidden events of step t - 1 (counts <= 31), neuron j = 0 .. N-1 in order: the same with
   ``weights_rec`` and ``weight_shift_rec`` onto the hidden neurons, and, for the last N_oen
   neurons (j = N - N_oen + i), with row i of ``weights_out`` and ``weight_shift_out`` onto the
   output neurons' single synapse. (So input -> hidden has no delay; hidden -> hidden and
   hidden -> output one step. Saturation happens per addition, so this order matters.)
3. every neuron, hidden ones first in index order, then output ones:
       decay(x, d) = x >> d (arithmetic), or sign(x) where that is 0
       Isyn_s -= decay(Isyn_s, dash_syn_s)                          (never overflows)
       dv = wrap(-decay(V, dash_mem))                               (-(-32768) wraps to -32768)
       dv = sat(dv + Isyn + Isyn2)                                  (the currents' sum is not saturated)
       dv = sat(dv + bias);  V = sat(V + dv)
       n = events already given to it this step (aliases); while V >= threshold and n < cap:
           n += 1; V = wrap(V - threshold)                          (cap 31 hidden, 1 output)
   after hidden neuron k, each of its alias targets a gets  n_a = min(n_a + n_k, 31): a target
   evolving later starts from those events (it may then emit fewer itself and subtract less);
   one that evolved earlier only has its count raised.
   The hidden counts are the events delivered in step t + 1; the output counts are the output.

States recorded per step (``record=True``) are those after step 3: Vmem, Isyn, Isyn2 and the
hidden counts (after all aliases), Vmem_out and Isyn_out, as XyloSim records them.

``reference_run`` states these rules literally in numpy (the batch as a vector; loops over
pre-synaptic neurons and, for events, over neurons in index order). ``emulate`` runs the same
rules in a compiled kernel (``_kernel.py``) over samples spread across threads: the fast path.
Both start every sample from zero state, as XyloSim after ``reset_all()``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.errors import SnnccError
from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.spec import XyloSpec

STATE_NAMES = ("vmem", "isyn", "isyn2", "spikes", "vmem_out", "isyn_out")


@dataclass
class XyloResult:
    """What a run gives: output event counts, and per-step states when recorded."""

    output_spikes: np.ndarray               # (B, T, Nout) uint8 output events per step (0 or 1)
    vmem: np.ndarray | None = None          # (B, T, N) int16 hidden membrane potentials
    isyn: np.ndarray | None = None          # (B, T, N) int16 hidden synaptic currents, synapse 1
    isyn2: np.ndarray | None = None         # (B, T, N) int16 hidden synaptic currents, synapse 2
    spikes: np.ndarray | None = None        # (B, T, N) uint8 hidden event counts (0 .. 31)
    vmem_out: np.ndarray | None = None      # (B, T, Nout) int16
    isyn_out: np.ndarray | None = None      # (B, T, Nout) int16

    @property
    def recorded(self) -> bool:
        return self.vmem is not None

    @property
    def counts(self) -> np.ndarray:
        """(B, Nout) output events summed over time."""
        return self.output_spikes.sum(axis=1, dtype=np.int64)

    def arrays(self) -> dict[str, np.ndarray]:
        """The result as named arrays (what a file of results holds)."""
        out = {"output_spikes": self.output_spikes}
        if self.recorded:
            out.update({name: getattr(self, name) for name in STATE_NAMES})
        return out


def wrap16(x):
    """Two's complement narrowing to the state width (``CORE.state_bits``), elementwise on int64."""
    half = np.int64(1) << (CORE.state_bits - 1)
    return ((np.asarray(x, np.int64) + half) & (2 * half - 1)) - half


def sat16(x):
    return np.clip(x, CORE.state_min, CORE.state_max)


def decay(x: np.ndarray, dash: np.ndarray) -> np.ndarray:
    """x >> dash (arithmetic, rounds toward -inf), replaced by sign(x) where it is 0."""
    d = np.right_shift(x, dash)
    return np.where(d == 0, np.sign(x), d)


def effective_weights(spec: XyloSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """int16(w << shift) for the three matrices, as int64 arrays of shapes (Nin, N_ien, 2),
    (N, N, 2) and (N_oen, Nout) (an absent synapse axis means synapse 1 only: zeros on synapse 2)."""
    def shifted(w, shift, syn_axis):
        w = np.asarray(w, np.int64)
        if syn_axis:
            if w.ndim == 2:
                w = w[:, :, None]
            w = np.concatenate([w, np.zeros(w.shape[:2] + (CORE.hidden_synapse_states - w.shape[2],), np.int64)],
                               axis=2)
        return wrap16(w << shift)

    return (shifted(spec.weights_in, spec.weight_shift_in, True), shifted(spec.weights_rec, spec.weight_shift_rec, True),
            shifted(spec.weights_out, spec.weight_shift_out, False))


def check_inputs(inputs, n_in: int, source: str | None = None) -> np.ndarray:
    """(T, Nin) or (B, T, Nin) event counts (whole numbers >= 0; bool, integer or float) ->
    (B, T, Nin) uint8, clipped to ``CORE.max_input_spikes`` per channel and step as the chip does."""
    from snncc.inputs import check_batch

    x = check_batch(inputs, n_in, spikes=False, source=source)
    if x.dtype.kind == "f" and not np.all(x == np.floor(x)):
        bad = x[x != np.floor(x)].reshape(-1)[0].item()
        raise SnnccError(f"input must hold whole event counts, found {bad!r}", file=source, field="input")
    if x.dtype.kind in "if" and x.size and x.min() < 0:
        raise SnnccError(f"input event counts must be >= 0, found {x.min().item()!r}", file=source, field="input")
    return np.minimum(x, CORE.max_input_spikes).astype(np.uint8)


def _fire(v: np.ndarray, threshold: int, n: np.ndarray, cap: int) -> tuple[np.ndarray, np.ndarray]:
    """while v >= threshold and n < cap: n += 1; v = wrap(v - threshold)  (vector over the batch)."""
    n = n.copy()
    while True:
        more = (v >= threshold) & (n < cap)
        if not more.any():
            return n, v
        n = n + more
        v = np.where(more, wrap16(v - threshold), v)


def _evolve_states(isyn: np.ndarray, v: np.ndarray, dash_syn: np.ndarray, dash_mem: np.ndarray,
                   bias: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Step 3 up to the events: decay the currents, integrate them and the bias into V."""
    isyn = isyn - decay(isyn, dash_syn)
    dv = wrap16(-decay(v, dash_mem))
    dv = sat16(dv + isyn.sum(axis=-1))
    dv = sat16(dv + bias)
    return isyn, sat16(v + dv)


def reference_run(spec: XyloSpec, inputs, *, record: bool = False) -> XyloResult:
    """The rules of this module's docstring, literally, in numpy (slow; the definition)."""
    x = check_inputs(inputs, spec.n_in).astype(np.int64)
    b, t_steps, n_in = x.shape
    n, n_out, n_ien, n_oen = spec.n_hidden, spec.n_out, spec.n_ien, spec.n_oen
    w_in, w_rec, w_out = effective_weights(spec)
    dash_syn = np.stack([spec.dash_syn, spec.dash_syn_2], axis=1).astype(np.int64)       # (N, 2)
    dash_mem, dash_mem_out = spec.dash_mem.astype(np.int64), spec.dash_mem_out.astype(np.int64)
    dash_syn_out = spec.dash_syn_out.astype(np.int64)[:, None]                             # (Nout, 1)
    bias, bias_out = spec.bias.astype(np.int64), spec.bias_out.astype(np.int64)
    cap_h, cap_o = CORE.max_hidden_spikes, CORE.max_output_spikes

    isyn = np.zeros((b, n, CORE.hidden_synapse_states), np.int64)
    v = np.zeros((b, n), np.int64)
    isyn_o = np.zeros((b, n_out, CORE.output_synapse_states), np.int64)
    v_o = np.zeros((b, n_out), np.int64)
    events = np.zeros((b, n), np.int64)          # hidden events of the previous step
    out = np.zeros((b, t_steps, n_out), np.uint8)
    rec = {name: np.zeros((b, t_steps, n_out if name.endswith("_out") else n),
                          np.uint8 if name == "spikes" else np.int16) for name in STATE_NAMES} if record else None

    for t in range(t_steps):
        for j in range(n_in):                                        # 1. input events, no delay
            isyn[:, :n_ien] = sat16(isyn[:, :n_ien] + x[:, t, j, None, None] * w_in[j])
        for j in range(n):                                           # 2. last step's hidden events
            isyn = sat16(isyn + events[:, j, None, None] * w_rec[j])
        for i in range(n_oen):
            isyn_o[:, :, 0] = sat16(isyn_o[:, :, 0] + events[:, n - n_oen + i, None] * w_out[i])
        isyn, v = _evolve_states(isyn, v, dash_syn, dash_mem, bias)  # 3. hidden neurons
        events = np.zeros((b, n), np.int64)
        for k in range(n):
            events[:, k], v[:, k] = _fire(v[:, k], int(spec.threshold[k]), events[:, k], cap_h)
            for a in spec.aliases[k]:
                events[:, a] = np.minimum(events[:, a] + events[:, k], cap_h)
        isyn_o, v_o = _evolve_states(isyn_o, v_o, dash_syn_out, dash_mem_out, bias_out)   # output neurons
        for m in range(n_out):
            fired, v_o[:, m] = _fire(v_o[:, m], int(spec.threshold_out[m]), np.zeros(b, np.int64), cap_o)
            out[:, t, m] = fired
        if record:
            rec["vmem"][:, t], rec["isyn"][:, t], rec["isyn2"][:, t] = v, isyn[:, :, 0], isyn[:, :, 1]
            rec["spikes"][:, t] = events
            rec["vmem_out"][:, t], rec["isyn_out"][:, t] = v_o, isyn_o[:, :, 0]
    return XyloResult(out, **(rec or {}))


def emulate(spec: XyloSpec, inputs, *, record: bool = False, threads: int | None = None,
            source: str | None = None) -> XyloResult:
    """Run ``inputs`` ((T, Nin) or (B, T, Nin) event counts) through ``spec`` on the compiled kernel.

    ``threads``: threads the samples are spread over (default ``NUMBA_NUM_THREADS``); each sample
    starts from zero state. Equal, spike for spike and state for state, to ``reference_run``."""
    from snncc.targets.xylo._kernel import prepare, run_prepared

    x = check_inputs(inputs, spec.n_in, source=source)
    return run_prepared(prepare(spec), x, record=record, threads=threads)
