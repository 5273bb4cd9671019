"""The Xylo v2 SNN core's arithmetic, literally, in numpy: as xylosim 0.1.3 computes it (docs/xylo.md).

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
pre-synaptic neurons and, for events, over neurons in index order): the definition. ``emulator.emulate``
runs the same rules in a compiled kernel (``kernel.py``) over samples spread across threads: the fast
path. Both start every sample from zero state, as XyloSim after ``reset_all()``.
"""

from __future__ import annotations


import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.emulation.result import STATE_NAMES, XyloResult
from snncc.targets.xylo.emulation.weights import effective_weights, wrap16, wrapped_weights
from snncc.targets.xylo.spec import XyloSpec

COUNTERS = {
    "input_clipped": "input counts above the cap of 15 (per channel and step)",
    "wrapped_weight_deliveries": "deliveries through a weight whose w << shift wrapped in int16",
    "current_saturations": "synaptic-current additions that saturated at -32768 or 32767",
    "vmem_saturations": "membrane updates (dv or V) that saturated",
    "decay_wraps": "dv = -decay(V) that wrapped (V = -32768 with dash_mem 0)",
    "threshold_wraps": "V - threshold that wrapped (thresholds <= 0)",
    "hidden_capped": "hidden neuron-steps that stopped at 31 events with V still >= threshold",
    "output_capped": "output neuron-steps that stopped at 1 event with V still >= threshold",
}


def sat16(x):
    return np.clip(x, CORE.state_min, CORE.state_max)


def decay(x: np.ndarray, dash: np.ndarray) -> np.ndarray:
    """x >> dash (arithmetic, rounds toward -inf), replaced by sign(x) where it is 0."""
    d = np.right_shift(x, dash)
    return np.where(d == 0, np.sign(x), d)


def check_inputs(inputs, n_in: int, source: str | None = None, *, clip: bool = True) -> np.ndarray:
    """(T, Nin) or (B, T, Nin) event counts (whole numbers >= 0; bool, integer or float) ->
    (B, T, Nin), clipped to ``CORE.max_input_spikes`` per channel and step as the chip does (uint8);
    ``clip=False``: unclipped, int64."""
    from snncc.targets.kit.inputs import check_batch

    x = check_batch(inputs, n_in, spikes=False, source=source)
    if x.dtype.kind == "f" and not np.all(x == np.floor(x)):
        bad = x[x != np.floor(x)].reshape(-1)[0].item()
        raise SnnccError(f"input must hold whole event counts, found {bad!r}", file=source, field="input")
    if x.dtype.kind in "if" and x.size and x.min() < 0:
        raise SnnccError(f"input event counts must be >= 0, found {x.min().item()!r}", file=source, field="input")
    if not clip:
        return x.astype(np.int64)
    return np.minimum(x, CORE.max_input_spikes).astype(np.uint8)


class _Counter(dict):
    """Counts of the rules that bit (COUNTERS); ``add`` is a no-op when counting is off."""

    def __init__(self, on: bool):
        super().__init__({k: 0 for k in COUNTERS} if on else {})
        self.on = on

    def add(self, name: str, mask) -> None:
        if self.on:
            self[name] += int(np.count_nonzero(mask))


def _saturate(x: np.ndarray, counter: _Counter, name: str) -> np.ndarray:
    counter.add(name, (x < CORE.state_min) | (x > CORE.state_max))
    return sat16(x)


def _fire(v: np.ndarray, threshold: int, n: np.ndarray, cap: int, counter: _Counter,
          capped: str) -> tuple[np.ndarray, np.ndarray]:
    """while v >= threshold and n < cap: n += 1; v = wrap(v - threshold)  (vector over the batch)."""
    n = n.copy()
    while True:
        more = (v >= threshold) & (n < cap)
        if not more.any():
            counter.add(capped, (v >= threshold) & (n >= cap))
            return n, v
        n = n + more
        counter.add("threshold_wraps", more & (wrap16(v - threshold) != v - threshold))
        v = np.where(more, wrap16(v - threshold), v)


def _evolve_states(isyn: np.ndarray, v: np.ndarray, dash_syn: np.ndarray, dash_mem: np.ndarray,
                   bias: np.ndarray, counter: _Counter) -> tuple[np.ndarray, np.ndarray]:
    """Step 3 up to the events: decay the currents, integrate them and the bias into V."""
    isyn = isyn - decay(isyn, dash_syn)
    leak = -decay(v, dash_mem)
    dv = wrap16(leak)
    counter.add("decay_wraps", dv != leak)
    dv = _saturate(dv + isyn.sum(axis=-1), counter, "vmem_saturations")
    dv = _saturate(dv + bias, counter, "vmem_saturations")
    return isyn, _saturate(v + dv, counter, "vmem_saturations")


def _deliver(isyn: np.ndarray, counts: np.ndarray, w: np.ndarray, wrapped: np.ndarray,
             counter: _Counter) -> np.ndarray:
    """isyn = sat(isyn + counts * w): ``counts`` (B, 1...) events of one pre-synaptic neuron."""
    if counter.on:
        counter.add("wrapped_weight_deliveries", (counts > 0) & wrapped)
    return _saturate(isyn + counts * w, counter, "current_saturations")


def reference_run(spec: XyloSpec, inputs, *, record: bool = False, count: bool = False) -> XyloResult:
    """The rules of this module's docstring, literally, in numpy (slow; the definition).

    ``count``: also count how often each rule that loses information bit (``COUNTERS``)."""
    x_raw = check_inputs(inputs, spec.n_in, clip=False)
    counter = _Counter(count)
    counter.add("input_clipped", x_raw > CORE.max_input_spikes)
    x = np.minimum(x_raw, CORE.max_input_spikes).astype(np.int64)
    b, t_steps, n_in = x.shape
    n, n_out, n_ien, n_oen = spec.n_hidden, spec.n_out, spec.n_ien, spec.n_oen
    w_in, w_rec, w_out = effective_weights(spec)
    wrap_in, wrap_rec, wrap_out = (m != 0 for m in wrapped_weights(spec))
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
            isyn[:, :n_ien] = _deliver(isyn[:, :n_ien], x[:, t, j, None, None], w_in[j], wrap_in[j], counter)
        for j in range(n):                                           # 2. last step's hidden events
            isyn = _deliver(isyn, events[:, j, None, None], w_rec[j], wrap_rec[j], counter)
        for i in range(n_oen):
            isyn_o[:, :, 0] = _deliver(isyn_o[:, :, 0], events[:, n - n_oen + i, None], w_out[i], wrap_out[i],
                                       counter)
        isyn, v = _evolve_states(isyn, v, dash_syn, dash_mem, bias, counter)   # 3. hidden neurons
        events = np.zeros((b, n), np.int64)
        for k in range(n):
            events[:, k], v[:, k] = _fire(v[:, k], int(spec.threshold[k]), events[:, k], cap_h, counter,
                                          "hidden_capped")
            for a in spec.aliases[k]:
                events[:, a] = np.minimum(events[:, a] + events[:, k], cap_h)
        isyn_o, v_o = _evolve_states(isyn_o, v_o, dash_syn_out, dash_mem_out, bias_out, counter)   # outputs
        for m in range(n_out):
            fired, v_o[:, m] = _fire(v_o[:, m], int(spec.threshold_out[m]), np.zeros(b, np.int64), cap_o, counter,
                                     "output_capped")
            out[:, t, m] = fired
        if record:
            rec["vmem"][:, t], rec["isyn"][:, t], rec["isyn2"][:, t] = v, isyn[:, :, 0], isyn[:, :, 1]
            rec["spikes"][:, t] = events
            rec["vmem_out"][:, t], rec["isyn_out"][:, t] = v_o, isyn_o[:, :, 0]
    return XyloResult(out, **(rec or {}), events=dict(counter) if count else None)
