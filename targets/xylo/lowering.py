"""IR graph -> Xylo spec dict (the keyword arguments of Rockpool's ``XyloSim.from_specification``).

The contract (Xylo Audio 2; N hidden neurons, Nin inputs, Nout outputs):

    weights_in   int8   (Nin, N, 2)   input -> hidden, last axis the synapse (one row per model input)
    weights_rec  int8   (N, N, 2)     hidden (pre) -> hidden (post), per synapse
    weights_out  int8   (N, Nout)     hidden -> output (N_oen = N: every hidden neuron's row)
    dash_mem, dash_syn, dash_syn_2    uint8 (N)     bit-shift decays, 0..15
    dash_mem_out, dash_syn_out        uint8 (Nout)
    threshold, bias                   int16 (N)
    threshold_out, bias_out           int16 (Nout)
    weight_shift_in, _rec, _out       int           left shifts, 0..8 (no int8 weight wraps in int16)
    aliases                           list of N empty lists
    dt                                float (s)

Lowering, in the IR's terms (``timing.py``, ``quantize.py``): the graph must be a chain that Xylo can
hold (``structure.py``); subtract reset (a zero reset is refused unless ``allow_reset_change``, then
subtract is deployed and the change recorded); refractory 1; recurrent IR delay 1. Populations run
``timing.shifts`` steps late; the chip is fed ``input_pad`` zero steps before a sample and read from
``output_lag`` on. The rule (``rule``) places hidden populations ``direct`` or ``single``; ``auto``
measures every candidate's argmax agreement with the float graph, the network spec run in snncc's bit-exact
emulator, on calibration inputs (their
second half; the first half fits) and keeps the best (ties: the first listed, the simpler), then fits
the chosen rule again on all of them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF
from snncc.passes.current_bias import current_biases
from snncc.passes.fold_linear import fold_linear
from snncc.targets.xylo import kernels, measure, quantize, relays
from snncc.targets.xylo.assemble import PopulationRecord, assemble, hidden_state_limit, output_state_limit
from snncc.targets.xylo.chip import CHIPS, XyloChip, get_chip
from snncc.targets.xylo.identify import delayed
from snncc.targets.xylo.structure import Population, populations
from snncc.targets.xylo.timing import XyloTiming, projection_delay, solve_timing
from snncc.targets.xylo.twin import spec_graph

RULES = ("auto", "direct", "single", "single-identified", "relayed")
DEFAULT_CALIBRATION_SAMPLES = 256
BOTH_CALIBRATION_SAMPLES = 1024   # --relays both: twice the relay columns to fit (Braille RSNN, 4 replicas: 256 samples
                                  # 0.849, 1024 samples 0.856 pooled over 7,272 held-out samples; docs/xylo_lowering.md)
RELAY_SETS = ("fast", "both")     # --relays: one relay set per source at the faster dash, or one at each dash
DEFAULT_STEPS = 256
DEFAULT_DENSITY = 0.08
IDENTIFY_SCALE = 2.0      # regression weight exp(-|V - theta| / (2 theta)) (0.5-4 measured; 2 among the best)
IDENTIFY_RIDGE = 1e-3     # pull towards the kernel fit, relative to the mean curvature
MAX_REPLICAS = 8          # --replicas: copies of the hidden network (each calibrated on its own inputs)
RELAYED_RIDGE = 1e-4      # relayed fits: pull towards zero (1e-3 to 3e-5 measured; 1e-4 among the best)
PROVISIONAL_SHIFTS = (0, 0)   # the input and recurrent shifts the relays' events are first computed under
PAIRS_TRIED = 2


@dataclass
class XyloLowered:
    """What lowering produced: the network spec, how the float graph maps onto it, and how well it agrees."""

    spec: dict[str, Any]
    chip: str
    dt: float
    rule: str
    timing: XyloTiming
    populations: list[PopulationRecord]
    trained: Graph                       # the model as given
    reference: Graph                     # the float graph deployed (its reset changed if allowed)
    twin: Graph                          # the network spec as an IR graph (chip time)
    candidates: dict[str, dict[str, Any]] = field(default_factory=dict)   # rule -> selection agreement
    changes: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    calibration: dict[str, Any] = field(default_factory=dict)
    real_time: dict[str, Any] = field(default_factory=dict)

    @property
    def xylo_spec(self):
        """The network spec as an ``XyloSpec`` (checked; ``save_npz`` writes spec.npz)."""
        from snncc.targets.xylo.spec import XyloSpec

        return XyloSpec(**self.spec)

    def chip_input(self, x: np.ndarray) -> np.ndarray:
        """IR inputs (B, T, C) as the chip must be fed (``input_pad`` zero steps before, enough after)."""
        return measure.chip_window(np.asarray(x), self.timing.input_pad, self.timing.output_lag)

    def read_output(self, chip_out: np.ndarray, steps: int) -> np.ndarray:
        return measure.read_window(np.asarray(chip_out), self.timing.output_lag, steps)

    def record(self) -> dict[str, Any]:
        """The quantization record (JSON-able)."""
        return {"chip": self.chip, "dt": self.dt, "rule": self.rule, "timing": self.timing.as_dict(),
                "populations": [p.as_dict() for p in self.populations], "candidates": self.candidates,
                "changes": list(self.changes), "notes": list(self.notes), "calibration": dict(self.calibration),
                "real_time": dict(self.real_time)}


@dataclass
class _Source:
    """Per population: the float graph's parameters and its calibration traces."""

    pop: Population
    alpha: np.ndarray
    beta: np.ndarray
    theta: np.ndarray
    bias_v: np.ndarray
    bias_i: np.ndarray
    w_ff: np.ndarray
    w_rec: np.ndarray | None
    d_ff: int
    bias_lag: int | None = None        # IR step from which the always-on source's spikes arrive (None: not usable)
    trains: dict[str, np.ndarray] = field(default_factory=dict)
    raw: dict[str, np.ndarray] = field(default_factory=dict)      # pre's and own spikes, undelayed (IR time)
    v_pre: np.ndarray | None = None


def _check_spike_rules(graph: Graph, pops: list[Population]) -> None:
    for p in pops:
        op = graph.node(p.lif)
        if not op.standard_spikes:
            raise SnnccError("the Xylo lowering takes models with the standard spike rule (one spike per step on "
                             f"V > threshold); this population has max_spikes {op.max_spikes}, fire_test "
                             f"'{op.fire_test}'", field=f"node '{p.lif}'")
        if np.any(~np.isfinite(op.threshold)):
            raise SnnccError("a non-spiking population (threshold +inf) cannot run on Xylo's spiking neurons",
                             field=f"node '{p.lif}'.threshold")


def _reset(graph: Graph, pops: list[Population], allow: bool) -> tuple[Graph, list[str]]:
    from snncc.passes.reset_change import change_reset

    return change_reset(graph, [p.lif for p in pops], from_="zero", to="subtract", allow=allow,
                        refusal="Xylo resets by subtracting the threshold and cannot reset to zero; pass "
                                "--allow-reset-change to deploy reset by subtraction (snncc check measures the cost)",
                        why="Xylo subtracts the threshold")


def _sources(g: Graph, pops: list[Population], timing: XyloTiming) -> list[_Source]:
    """The source's spikes (chip steps 0, 1, ...) reach every population at chip step 1: IR step 1 - shift."""
    out = []
    for p in pops:
        op = g.node(p.lif)
        alpha, beta = op.decays(g.dt)
        bias_v = op.bias if (op.bias is not None and op.bias_placement == "voltage") else np.zeros(op.n)
        bias_i = np.zeros(op.n)
        for term in current_biases(g, p.lif):
            bias_i = bias_i + term.vector
        out.append(_Source(p, np.asarray(alpha, float), np.asarray(beta, float), op.threshold.astype(float),
                           np.asarray(bias_v, float), bias_i, g.node(p.ff).weight,
                           None if p.rec is None else g.node(p.rec).weight, projection_delay(g, p.pre, p.ff, p.lif),
                           1 - timing.shifts[p.lif] if timing.shifts[p.lif] <= 1 else None))
    return out


def _calibrate(ref: Graph, sources: list[_Source], x: np.ndarray) -> None:
    """Teacher-forcing traces: each population's delayed presynaptic and own spike trains, pre-reset voltages."""
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    with one_thread():
        res = simulate(ref, x, record="all")
    trains = {sources[0].pop.pre: np.asarray(x, np.float64)}
    for s in sources:
        trains[s.pop.lif] = np.asarray(res.spikes[s.pop.lif])
    ones = np.ones(np.shape(x)[:2] + (1,))
    for s in sources:
        s.trains = {s.pop.pre: delayed(trains[s.pop.pre], s.d_ff), s.pop.lif: delayed(trains[s.pop.lif], 1)}
        s.raw = {s.pop.pre: trains[s.pop.pre], s.pop.lif: trains[s.pop.lif]}
        if s.bias_lag is not None:
            s.trains[quantize.BIAS_SOURCE] = delayed(ones, s.bias_lag)
        s.v_pre = np.asarray(res.voltage[s.pop.lif]) + s.theta * trains[s.pop.lif]


def _float_counts(ref: Graph, x: np.ndarray, last: str) -> np.ndarray:
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    with one_thread():
        return np.asarray(simulate(ref, x, record="spikes").spikes[last]).sum(axis=1)


def twin_counts(twin: Graph, timing: XyloTiming, x: np.ndarray) -> np.ndarray:
    """Output spike counts of the network spec's float twin over the IR's T steps of ``x``."""
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    chip_x = measure.chip_window(np.asarray(x), timing.input_pad, timing.output_lag)
    with one_thread():
        out = np.asarray(simulate(twin, chip_x, record="spikes").spikes["output"])
    return measure.read_window(out, timing.output_lag, x.shape[1]).sum(axis=1)


def _hidden(s: _Source, method: str, dashes: tuple[int, int] | None) -> quantize.HiddenFloat:
    srcs = {s.pop.pre: s.w_ff}
    if s.w_rec is not None:
        srcs[s.pop.lif] = s.w_rec
    if method == "direct":
        return quantize.hidden_direct(s.pop.lif, s.alpha, s.beta, s.theta, srcs, s.bias_v, s.bias_i)
    return quantize.hidden_single(s.pop.lif, s.alpha, s.beta, s.theta, srcs, dashes, s.bias_v, s.bias_i, s.bias_lag)


def build_candidate(sources: list[_Source], n_inputs: int, method: str, pairs: list[tuple[int, int]] | None,
                    identified: bool, chip: XyloChip, timing: XyloTiming | None = None,
                    relayed: bool = False, readout: str = "output",
                    replicas: list[list[_Source]] = (),
                    rounding: str | None = None, both_dashes: bool = False) -> tuple[dict, list[PopulationRecord]]:
    """A spec for one rule: hidden populations ``method`` (single: dash pair per population, kernel or
    identified weights, rounding with error feedback), the readout population on the output neurons
    (``readout`` "output"), or on hidden neurons like the others, copied exactly to the output neurons one
    step later ("hidden": ``assemble._copy_readout``; ``pairs`` then has one more entry).
    ``relayed`` (identified single populations only): sigma-delta relays (``relays.py``) give every hidden
    population a third basis function; their events depend on the matrices' shifts: fitted under
    ``PROVISIONAL_SHIFTS``, and fitted again under the shifts the assembly chose if they differ (then kept).
    Relayed fits are pulled
    towards zero, not towards the two-exponential kernel: its cancelling coefficients (about 7 thresholds
    per unit weight on the Braille RSNN) cost more in int8 rounding than they gain (docs/xylo_lowering.md).
    ``replicas``: more copies of ``sources``, each calibrated on its own inputs (``replica_sources``): every
    hidden population is placed once per copy, fitted and rounded on that copy's inputs (copy k's relays a step
    coarser, ``replica_events_max``), and the readout takes each copy's spikes with 1/K of its weights
    (``readout`` "output" only; ``merge_replica_records`` folds the copies' records into one per population).
    ``rounding``: "none" leaves the weights unrounded (``assemble``); else the method's own rounding.
    ``both_dashes``: every relayed source gets relays at both synapse dashes (``relay_plan``)."""
    copies = [sources] + list(replicas)
    k_all = len(copies)
    if k_all > 1 and readout != "output":
        raise SnnccError("internal check failed: replicas need the readout on the output neurons", field="rule")
    on_hidden = [c if readout == "hidden" else c[:-1] for c in copies]
    plans = [relay_plan(h, pairs, replica_events_max(k), both_dashes) if relayed else []
             for k, h in enumerate(on_hidden)]
    shifts: tuple[int, int] | None = None
    ridge = RELAYED_RIDGE if relayed else IDENTIFY_RIDGE
    for _ in range(2 if plans[0] else 1):
        per_copy, plan, limits = [], [], {}
        for k, (hid, copy_plan) in enumerate(zip(on_hidden, plans)):
            if copy_plan:
                if timing is None:
                    raise SnnccError("internal check failed: a relayed candidate needs the lowering's timing",
                                     field="rule")
                relay_trains(hid, copy_plan, timing, shifts)
            pops = [_fit_hidden(s, method, None if pairs is None else pairs[i], identified, copy_plan, ridge)
                    for i, s in enumerate(hid)]
            lims = [hidden_state_limit(p, s.trains, s.v_pre) for p, s in zip(pops, hid)]
            if k_all > 1:
                copy_plan = _as_replica(pops, copy_plan, k)
            limits.update({p.name: lim for p, lim in zip(pops, lims)})
            per_copy.append(pops)
            plan += copy_plan
        hidden = [pops[i] for i in range(len(per_copy[0])) for pops in per_copy]     # a population's copies adjoin
        if readout == "hidden":
            out, out_limit = None, None
        else:
            out, out_limit = _fit_output(sources[-1], identified, k_all)
        spec, records = assemble(hidden, out, n_inputs, sources[0].pop.pre, limits, out_limit,
                                 rounding or ("feedback" if method == "single" else "nearest"),
                                 relays=plan, shifts=shifts)
        chosen = (int(spec["weight_shift_in"]), int(spec["weight_shift_rec"]))
        if chosen == (shifts or PROVISIONAL_SHIFTS):
            break                                  # the relays' events were computed under these shifts
        shifts = chosen
    if chip.synapses_per_hidden < 2:          # one synaptic current: the weights' last axis has one entry
        spec["weights_in"], spec["weights_rec"] = spec["weights_in"][:, :, :1], spec["weights_rec"][:, :, :1]
    if k_all > 1:
        records = merge_replica_records(records, k_all)
    return spec, records


def _fit_hidden(s: _Source, method: str, dashes: tuple[int, int] | None, identified: bool,
                plan: list[relays.Relay], ridge: float) -> quantize.HiddenFloat:
    """One population on hidden neurons, fitted on ``s``'s calibration traces."""
    pop = _hidden(s, method, dashes)
    if plan:
        pop = _with_relays(pop, s, plan)
    if method == "single":
        if identified:
            return quantize.identify_hidden(pop, s.trains, s.v_pre, IDENTIFY_SCALE, ridge)
        return quantize.hidden_hessians(pop, s.trains, s.v_pre, IDENTIFY_SCALE, ridge)
    return pop


def _fit_output(last: _Source, identified: bool, copies: int) -> tuple[quantize.OutputFloat, np.ndarray]:
    """The readout population on the output neurons, fitted on ``last``'s traces; with ``copies`` > 1 its
    presynaptic population is placed ``copies`` times (``_as_replica`` names): each copy's spikes with 1/copies
    of the weights (the copies' columns are equal, so the fit and the rounding with error feedback share each
    weight among them)."""
    out = quantize.output_native(last.pop.lif, last.pop.pre, last.alpha, last.beta, last.theta, last.w_ff,
                                 last.bias_v, last.bias_i, bias_source=last.bias_lag == 0)
    pre = last.trains[last.pop.pre]
    if copies > 1:
        n_src = pre.shape[2]
        out.source = replica_name(last.pop.pre, 0)
        out.weight = np.concatenate([out.weight[:, :n_src] / copies] * copies + [out.weight[:, n_src:]], axis=1)
        pre = np.concatenate([pre] * copies, axis=2)
    if out.bias_source:
        pre = np.concatenate([pre, last.trains[quantize.BIAS_SOURCE]], axis=2)
    if identified:
        out = quantize.identify_output(out, pre, _own(last), last.v_pre, IDENTIFY_SCALE, IDENTIFY_RIDGE)
    return out, output_state_limit(out, pre, last.v_pre)


# -- replicas ------------------------------------------------------------------------------------------------
REPLICA_SEED_STRIDE = 7919     # copy k calibrates on seed + k * stride (seeded random inputs)
REPLICA_EVENTS_STEP = 4        # copy k's relays: EVENTS_MAX - 4 k events a step at most (a different quantization)
REPLICA_EVENTS_MIN = 14


def replica_name(name: str, k: int) -> str:
    """The name copy ``k`` of a population (or of its relays' source) takes inside a replicated spec."""
    return f"{name}#{k}"


def replica_events_max(k: int) -> int:
    """Copy k's relays quantize a step coarser than copy k - 1's, so the copies' relay errors differ (measured on
    the Braille RSNN, 4 copies, hidden spikes read by the float readout: 0.850 with equal relays, 0.857 with
    30 / 26 / 22 / 18 events)."""
    return max(relays.EVENTS_MAX - REPLICA_EVENTS_STEP * k, REPLICA_EVENTS_MIN)


def _as_replica(pops: list[quantize.HiddenFloat], plan: list[relays.Relay], k: int) -> list[relays.Relay]:
    """Rename copy ``k``'s populations, the sources they read and their relays (``replica_name``; the input and the
    bias source stay shared), in place; returns copy k's relays under their new names."""
    names = {p.name: replica_name(p.name, k) for p in pops}
    renamed = dict(names)
    out = []
    for r in plan:
        source = names.get(r.source, r.source)
        new = relays.Relay(source, r.n, r.dash, r.events_max, tag="" if source != r.source else f"#{k}",
                           second=r.second)
        renamed[r.name] = new.name
        out.append(new)
    for p in pops:
        p.name = renamed[p.name]
        p.weights = {renamed.get(src, src): w for src, w in p.weights.items()}
        p.columns = [(renamed.get(src, src), syn) for src, syn in p.columns]
    return out


def merge_replica_records(records: list[PopulationRecord], copies: int) -> list[PopulationRecord]:
    """One record per population over its adjoining copies (``copies`` set; units concatenated, gains spread over
    all of them), in the place of its first copy; relay records keep their copy's name."""
    groups: dict[str, list[PopulationRecord]] = {}
    order: list[PopulationRecord | str] = []
    for r in records:
        base, sep, k = r.name.rpartition("#")
        if r.role == "relay" or not sep or not k.isdigit():
            order.append(r)
            continue
        if base not in groups:
            groups[base] = []
            order.append(base)
        groups[base].append(r)
    out = []
    for item in order:
        if isinstance(item, PopulationRecord):
            out.append(item)
            continue
        parts = groups[item]
        first = parts[0]
        units = tuple(u for p in parts for u in p.units)
        size = first.neurons[1] - first.neurons[0]
        out.append(PopulationRecord(
            item, first.role, first.method, (first.neurons[0], parts[-1].neurons[1]), first.dashes, first.fit,
            first.rounding, {"min": float(min(units)), "median": float(np.median(units)), "max": float(max(units))},
            list(dict.fromkeys(n for p in parts for n in p.notes))
            + [f"{copies} replicas of {size} neurons each, side by side"], units=units, copies=copies))
    return out


def _with_relays(pop: quantize.HiddenFloat, s: _Source, plan: list[relays.Relay]) -> quantize.HiddenFloat:
    """``pop`` with its prior weights at zero and a zero prior for each relay source that reaches it (the
    identification fits them all)."""
    pop.weights = {k: np.zeros_like(v) for k, v in pop.weights.items()}
    for r in plan:
        if r.name in s.trains:
            pop.weights[r.name] = np.zeros((2, pop.n, r.n))
    pop.columns = [(src, k) for k in range(2) for src in pop.weights]
    return pop


# -- relays ------------------------------------------------------------------------------------------------
def relay_plan(hidden: list[_Source], pairs: list[tuple[int, int]] | None,
               events_max: int = relays.EVENTS_MAX, both: bool = False) -> list[relays.Relay]:
    """The relays a relayed candidate adds to the populations on ``hidden`` neurons: one per channel of the
    input and of every hidden population that feeds a hidden population (its own recurrence or the next one);
    each takes the *faster* synapse dash of the first population it feeds: relayed through the slower one, its
    events give the cascade a_fast then a_slow, the shape of a CUBA neuron's kernel (the current's decay, then
    the membrane's). Measured on the Braille RSNN over three calibration seeds: 0.822 agreement on random inputs,
    0.914 on the Braille letters, against 0.804 / 0.894 with the slower dash.

    ``both`` (``--relays both``): every source gets a second relay set at the *slower* dash too, so each target
    sees the cascades of both grid poles: the basis a^n, n a^n, b^n, n b^n (two of each pole). On the Braille
    RSNN's kernels (poles 0.75 and 0.85) the least-squares error of the kernel falls from 2 % to 0.2 %; the fit
    has twice the relay columns and needs more calibration (``BOTH_CALIBRATION_SAMPLES``)."""
    def relays_of(source: str, width: int, fed: int) -> list[relays.Relay]:
        """``source``'s relay sets at the dashes of population ``fed`` (the faster; with ``both`` the slower too)."""
        pair = tuple(int(v) for v in pairs[fed]) if pairs is not None else (2, 3)
        dashes = pair[:2] if both and pair[0] != pair[1] else pair[:1]
        return [relays.Relay(source, width, d, events_max, second=i > 0) for i, d in enumerate(dashes)]

    plan = []
    for k, s in enumerate(hidden):
        if k == 0:
            plan += relays_of(s.pop.pre, s.raw[s.pop.pre].shape[2], 0)
        if s.pop.rec is not None or k + 1 < len(hidden):
            plan += relays_of(s.pop.lif, s.raw[s.pop.lif].shape[2], k if s.pop.rec is not None else k + 1)
    return plan


def relay_trains(hidden: list[_Source], plan: list[relays.Relay], timing: XyloTiming,
                 shifts: tuple[int, int] | None) -> None:
    """Each hidden population's relay trains in its IR time: relay events of source Q (chip rules, the registers
    under ``shifts``, else ``PROVISIONAL_SHIFTS``) reach population P ``d + 1 + s_Q - s_P`` steps after Q's IR
    step (d: Q -> relay, 0 from the input, 1 from hidden neurons; relay -> P: 1)."""
    from snncc.targets.xylo.timing import CHIP_DELAY_HIDDEN, CHIP_DELAY_INPUT

    first_pre = hidden[0].pop.pre
    events: dict[str, np.ndarray] = {}          # each relay set run once, whichever populations it reaches
    for s in hidden:
        for r in plan:
            if r.source not in (s.pop.pre, s.pop.lif if s.pop.rec is not None else None):
                continue
            is_input = r.source == first_pre
            if r.name not in events:
                shift = (shifts or PROVISIONAL_SHIFTS)[0 if is_input else 1]
                w8, theta = r.registers(shift)
                events[r.name] = relays.relay_events(s.raw[r.source], r.dash, w8, shift, theta).astype(np.float64)
            lag = (CHIP_DELAY_INPUT if is_input else CHIP_DELAY_HIDDEN) + CHIP_DELAY_HIDDEN \
                + timing.shifts[r.source] - timing.shifts[s.pop.lif]
            s.trains[r.name] = delayed(events[r.name], lag)


def _emulate(spec: dict, chip_x: np.ndarray) -> np.ndarray:
    """Output spikes of ``spec`` in snncc's bit-exact emulator (``emulator.py``)."""
    from snncc.targets.xylo.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    return emulate(XyloSpec(**spec), chip_x).output_spikes


def _event_rates(spec: dict, chip_x: np.ndarray) -> dict[str, float]:
    """The share of channel- and neuron-steps with an event, ``spec`` run on the chip inputs (every hidden neuron:
    relays and copies too), for the real-time estimate; several events of one neuron in one step count once,
    as the cycle model states its rates (``rules.cycles_per_step``)."""
    from snncc.targets.xylo.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    run = emulate(XyloSpec(**spec), chip_x, record=True)
    return {"input": float(np.mean(chip_x > 0)), "hidden": float(np.mean(run.spikes > 0)),
            "output": float(np.mean(run.output_spikes > 0))}


def _bias_notes(sources: list[_Source], records: list[PopulationRecord], timing: XyloTiming) -> list[str]:
    """What the chip makes of each population's biases (exact, or how it differs)."""
    out = []
    method = {r.name: r.method for r in records}
    for k, s in enumerate(sources):
        if not (np.any(s.bias_v) or np.any(s.bias_i)):
            continue
        name, late = s.pop.lif, timing.shifts[s.pop.lif]
        if k < len(sources) - 1 and method[name] == "single" and s.bias_lag is not None:
            out.append(f"{name}: biases carried by its bias register (step 0) and the always-on source neuron "
                       "(from step 1): exact up to the kernel fit")
        elif k == len(sources) - 1 and s.bias_lag == 0:
            if np.any(s.bias_i):
                out.append(f"{name}: current bias carried by the always-on source neuron: exact")
            if np.any(s.bias_v):
                out.append(f"{name}: voltage bias register acts from the chip's first step, {late} step(s) before "
                           "the population's IR step 0 (a decaying difference at the start of each sample)")
        else:
            out.append(f"{name}: biases enter as the constant voltage they settle to"
                       + (f", from the chip's first step ({late} step(s) early)" if late else "")
                       + ": the first steps of a sample differ")
    return out


def _own(s: _Source) -> np.ndarray:
    """A population's own spikes, undelayed (its trains hold them delayed by 1)."""
    own = s.trains[s.pop.lif]
    out = np.zeros_like(own)
    out[:, :-1] = own[:, 1:]
    return out


@dataclass(frozen=True)
class Candidate:
    """One way to lower: ``method`` for the hidden populations (dash ``pairs`` per population placed on hidden
    neurons), ``identified`` weights, ``relayed`` (sigma-delta relays), the readout on the output neurons
    ("output") or on hidden neurons copied to them ("hidden")."""

    name: str
    method: str
    pairs: list | None = None
    identified: bool = False
    relayed: bool = False
    readout: str = "output"
    both_dashes: bool = False      # relays at both synapse dashes (``--relays both``)


def candidate_rules(sources: list[_Source], rule: str, chip: XyloChip, replicas: int = 1,
                    both: bool = False) -> list[Candidate]:
    """The candidates of ``rule`` (``single`` needs two synaptic currents per hidden neuron: not on Xylo IMU;
    ``relayed`` also needs room for its relays, and tries the readout on hidden neurons where they fit, except
    with ``replicas``, whose copies the output neurons read; ``both``: relays at both synapse dashes)."""
    if chip.synapses_per_hidden < 2:
        if rule not in ("auto", "direct"):
            raise SnnccError(f"the {rule} rule needs two synaptic currents per hidden neuron; {chip.name} has "
                             f"{chip.synapses_per_hidden} (use --rule direct)", field="--rule")
        return [Candidate("direct", "direct")]
    fits = [kernels.best_pairs(float(np.median(s.alpha)), float(np.median(s.beta)), PAIRS_TRIED) for s in sources]
    out: list[Candidate] = []
    if rule in ("auto", "direct"):
        out.append(Candidate("direct", "direct"))
    for k in range(PAIRS_TRIED if rule == "auto" else 1):
        every = [f[min(k, len(f) - 1)].dashes for f in fits]
        pairs = every[:-1]
        label = "/".join(f"{a},{b}" for a, b in pairs)
        if rule in ("auto", "single"):
            out.append(Candidate(f"single dashes {label}", "single", pairs))
        if rule in ("auto", "single-identified"):
            out.append(Candidate(f"single-identified dashes {label}", "single", pairs, identified=True))
        if rule in ("auto", "relayed") and k == 0:      # the best pair only (a relayed fit costs ~10 s)
            room = relay_room(sources[:-1], pairs, chip, both=both)
            tail = ", relays at both dashes" if both else ""
            if room is None:
                out.append(Candidate(f"relayed dashes {label}{tail}", "single", pairs, True, True, both_dashes=both))
            elif rule == "relayed":
                raise SnnccError(room, field="--rule")
            if replicas == 1 and relay_room(sources, every, chip, copies=len(sources[-1].theta), both=both) is None:
                out.append(Candidate(f"relayed dashes {label}{tail}, readout on hidden neurons "
                                     f"(dashes {every[-1][0]},{every[-1][1]}) copied to the output neurons",
                                     "single", every, True, True, "hidden", both))
    return out


def relay_room(hidden: list[_Source], pairs: list[tuple[int, int]], chip: XyloChip, copies: int = 0,
               both: bool = False) -> str | None:
    """None when the populations on ``hidden`` neurons, their relays, the readout's ``copies`` and the bias
    source fit ``chip``'s hidden neurons and its input and output expansion (conservatively: every hidden
    neuron within both), else why not, in one line."""
    plan = relay_plan(hidden, pairs, both=both)
    used = sum(len(s.theta) for s in hidden) + copies + 1
    total = used + sum(r.n for r in plan)
    if total > chip.max_hidden:
        return (f"the relayed rule needs {total} hidden neurons (populations, {sum(r.n for r in plan)} relays, the "
                f"bias source); {chip.name} has {chip.max_hidden}")
    if total > chip.max_input_expansion or total > chip.max_output_expansion:
        return (f"the relayed rule places {total} hidden neurons; {chip.name} lets input weights reach the first "
                f"{chip.max_input_expansion} and output weights leave the last {chip.max_output_expansion}")
    return None


def replica_room(spec: dict[str, Any], replicas: int, chip: XyloChip) -> str | None:
    """None when ``replicas`` copies of ``spec``'s hidden neurons (the bias source shared) fit ``chip``, else why
    not, in one line."""
    if replicas == 1:
        return None
    n = int(np.asarray(spec["threshold"]).size)
    bias_source = int(_has_bias_source(spec))
    total = replicas * (n - bias_source) + bias_source
    if total > min(chip.max_hidden, chip.max_input_expansion, chip.max_output_expansion):
        return (f"{replicas} replicas need {total:,} hidden neurons ({n - bias_source} each"
                f"{' and the bias source' if bias_source else ''}); {chip.name} has {chip.max_hidden:,}"
                + ("" if chip.max_input_expansion >= total and chip.max_output_expansion >= total else
                   f" and lets input weights reach {chip.max_input_expansion} and output weights leave "
                   f"{chip.max_output_expansion}"))
    return None


def _has_bias_source(spec: dict[str, Any]) -> bool:
    """Whether the last hidden neuron is the always-on bias source (no input, memoryless, V = bias = threshold)."""
    k = int(np.asarray(spec["threshold"]).size) - 1
    return bool(k >= 0 and not np.any(spec["weights_in"][:, k]) and not np.any(spec["weights_rec"][:, k])
                and int(spec["dash_mem"][k]) == 0 and int(spec["bias"][k]) == int(spec["threshold"][k])
                == quantize.SINGLE_THRESHOLD)


def replica_sources(ref: Graph, sources: list[_Source], opts: dict[str, Any], x: np.ndarray,
                    replicas: int) -> list[list[_Source]]:
    """Copies 1 .. replicas-1 of ``sources``, each calibrated on its own inputs: seeded random inputs of seed
    ``seed + k * REPLICA_SEED_STRIDE`` (as the calibration inputs), or, for given inputs, a seeded resample of
    them with replacement."""
    out = []
    seed = int(opts.get("seed", 1))
    for k in range(1, replicas):
        if opts.get("calibration") is not None:
            rng = np.random.default_rng(seed + k * REPLICA_SEED_STRIDE)
            xk = x[rng.integers(0, x.shape[0], x.shape[0])]
        else:
            xk = _calibration_inputs(dict(opts, seed=seed + k * REPLICA_SEED_STRIDE), x.shape[2])
        copy = [replace(s, trains={}, raw={}, v_pre=None) for s in sources]
        _calibrate(ref, copy, xk)
        out.append(copy)
    return out


def lowering_settings(options: Any) -> dict[str, Any]:
    """A target option record (``capabilities.XyloOptions``) as the settings ``lower`` reads (None: its default)."""
    return {k: v for k, v in options.as_dict().items() if k != "source" and v is not None}


def lower(graph: Graph, options: dict[str, Any] | None = None) -> XyloLowered:
    """Lower ``graph`` for a Xylo chip. Options: chip (a key of ``chip.CHIPS``, default "syns61201"), rule
    (RULES), allow_reset_change, calibration (an array (B, T, C) of 0/1 spikes) or calibration_samples /
    time_steps / density / seed;
    emulator: a callable (spec dict, chip inputs) -> output spikes that measures candidates (default: snncc's
    bit-exact emulator); rounding: "none" leaves every weight unrounded (a float spec in chip units that only the float
    twin runs: a measurement of what rounding costs, bench/xylo_loss_sources.py; it needs ``emulator``, and such a
    spec is neither checked against the chip's rules nor estimated for real time)."""
    opts = dict(options or {})
    try:
        chip = get_chip(opts.get("chip"))
    except KeyError:
        raise SnnccError(f"chip must be one of {', '.join(CHIPS)}", field="--chip") from None
    rule = opts.get("rule") or "auto"
    if rule not in RULES:
        raise SnnccError(f"rule must be one of {', '.join(RULES)}", field="--rule")
    replicas = 1 if opts.get("replicas") is None else int(opts["replicas"])
    if not 1 <= replicas <= MAX_REPLICAS:
        raise SnnccError(f"replicas must be a whole number from 1 to {MAX_REPLICAS}", field="--replicas")
    both = _relays_both(opts)
    unrounded = opts.get("rounding") == "none"
    if opts.get("rounding") not in (None, "none"):
        raise SnnccError("rounding must be 'none' or left out", field="rounding")
    if unrounded and opts.get("emulator") is None:
        raise SnnccError("an unrounded spec needs an emulator that runs float weights (the twin)", field="rounding")
    from snncc.targets.xylo import rules as design_rules

    trained = graph
    g, fold = fold_linear(graph)
    pops = populations(g)
    _check_spike_rules(g, pops)
    ref, changes = _reset(g, pops, bool(opts.get("allow_reset_change", False)))
    design_rules.check_graph(ref, pops, chip)
    timing = solve_timing(ref, pops)
    sources = _sources(ref, pops, timing)
    n_in = ref.node(pops[0].pre).width
    x = _calibration_inputs(opts, n_in)
    half = max(1, x.shape[0] // 2)
    fit_x, sel_x = x[:half], x[half:] if x.shape[0] > 1 else x
    _calibrate(ref, sources, fit_x)
    float_sel = _float_counts(ref, sel_x, pops[-1].lif)
    candidates: dict[str, dict[str, Any]] = {}
    emulator = opts.get("emulator")      # (spec, chip inputs (B, T', C)) -> output spikes (B, T', Nout); None: the twin
    best = None
    readout_timing = {"output": timing, "hidden": solve_timing(ref, pops, readout_extra=1)}

    def selection_agreement(spec: dict, at: XyloTiming) -> measure.Agreement:
        """``spec`` run on the selection half (the given emulator, else snncc's), against the float graph."""
        chip_x = measure.chip_window(sel_x, at.input_pad, at.output_lag)
        out = emulator(spec, chip_x) if emulator is not None else _emulate(spec, chip_x)
        return measure.agreement(measure.read_window(np.asarray(out), at.output_lag, sel_x.shape[1]).sum(axis=1),
                                 float_sel)

    for cand in candidate_rules(sources, rule, chip, replicas, both):
        ctiming = readout_timing[cand.readout]
        spec, records = build_candidate(sources, n_in, cand.method, cand.pairs, cand.identified, chip, ctiming,
                                        cand.relayed, cand.readout, rounding=opts.get("rounding"),
                                        both_dashes=cand.both_dashes)
        spec["dt"] = float(ref.dt)
        twin = spec_graph(spec, ref.dt)
        agr = selection_agreement(spec, ctiming)
        candidates[cand.name] = agr.as_dict()
        if best is None or agr.agreement > best[0].agreement:
            best = (agr, cand, spec, records, twin)
    agr, chosen, spec, records, twin = best
    name, timing = chosen.name, readout_timing[chosen.readout]
    if replicas > 1 or (x.shape[0] > 1 and bool(opts.get("refit", True))):
        # the chosen rule, fitted again on every calibration sample (the selection half too); replicas: each
        # further copy on its own inputs
        room = replica_room(spec, replicas, chip)
        if room:
            raise SnnccError(room, field="--replicas")
        _calibrate(ref, sources, x)
        extra = replica_sources(ref, sources, opts, x, replicas)
        spec, records = build_candidate(sources, n_in, chosen.method, chosen.pairs, chosen.identified, chip, timing,
                                        chosen.relayed, chosen.readout, extra, rounding=opts.get("rounding"),
                                        both_dashes=chosen.both_dashes)
        spec["dt"] = float(ref.dt)
        twin = spec_graph(spec, ref.dt)
        if replicas > 1:
            name = f"{name}, {replicas} replicas"
            candidates[name] = dict(selection_agreement(spec, timing).as_dict(),
                                    note="the selection half is among this spec's calibration inputs")
    notes = list(timing.notes) + fold.notes()
    real_time: dict[str, Any] = {"note": "not estimated: the weights are unrounded (a measurement, not a spec)"}
    if not unrounded:
        design_rules.check_spec(spec, chip)
        rates = _event_rates(spec, measure.chip_window(x, timing.input_pad, timing.output_lag))
        rt = design_rules.real_time(spec, float(ref.dt), rates)
        notes.append(rt.line())
        real_time = rt.as_dict()
    notes += _bias_notes(sources, records, timing)
    if any(r.method == "direct" for r in records):
        notes.append("direct rule: a hidden neuron fires up to 31 spikes per step on the chip where the IR fires one "
                     "(the deployed graph states it: max_spikes 31, fire_test '>=')")
    return XyloLowered(spec=spec, chip=chip.key, dt=float(ref.dt), rule=name, timing=timing, populations=records,
                       trained=trained, reference=ref, twin=twin, candidates=candidates, changes=changes, notes=notes,
                       calibration={"inputs": _describe(opts, x), "fit_samples": int(fit_x.shape[0]),
                                    "selection_samples": int(sel_x.shape[0]), "metric": "argmax agreement with the "
                                    "float graph over clear-winner samples, of the network spec run in "
                                    + ("the given emulator" if emulator is not None else "snncc's bit-exact emulator"),
                                    **({"replicas": replicas, "replica_inputs": _describe_replicas(opts)}
                                       if replicas > 1 else {})},
                       real_time=real_time)


def _calibration_inputs(opts: dict[str, Any], width: int) -> np.ndarray:
    given = opts.get("calibration")
    if given is not None:
        x = np.asarray(given)
        if x.ndim != 3 or x.shape[2] != width:
            raise SnnccError(f"calibration inputs must be (samples, steps, {width})", field="calibration")
        return (x > 0).astype(np.uint8)
    samples = int(opts.get("calibration_samples")
                  or (BOTH_CALIBRATION_SAMPLES if _relays_both(opts) else DEFAULT_CALIBRATION_SAMPLES))
    steps = int(opts.get("time_steps") or DEFAULT_STEPS)
    density = float(opts.get("density") or DEFAULT_DENSITY)
    seed = int(opts.get("seed", 1))
    if not 0 < density <= 1:
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    return (np.random.default_rng(seed).random((samples, steps, width)) < density).astype(np.uint8)


def _relays_both(opts: dict[str, Any]) -> bool:
    """``relays`` "both" (relays at both synapse dashes) or "fast" / left out (one set, the faster dash)."""
    value = opts.get("relays") or "fast"
    if value not in RELAY_SETS:
        raise SnnccError(f"relays must be one of {', '.join(RELAY_SETS)}", field="--relays")
    return value == "both"


def _describe_replicas(opts: dict[str, Any]) -> str:
    seed = int(opts.get("seed", 1))
    how = ("a seeded resample (with replacement) of the given spike trains, seed"
           if opts.get("calibration") is not None else "seeded random spike trains as copy 0's, seed")
    return (f"copy 0: the calibration inputs; copy k: {how} {seed} + {REPLICA_SEED_STRIDE} k; copy k's relays at most "
            f"{relays.EVENTS_MAX} - {REPLICA_EVENTS_STEP} k events a step (at least {REPLICA_EVENTS_MIN})")


def _describe(opts: dict[str, Any], x: np.ndarray) -> str:
    if opts.get("calibration") is not None:
        return f"{x.shape[0]} given spike trains of {x.shape[1]} steps"
    return (f"{x.shape[0]} seeded random spike trains (density {float(opts.get('density') or DEFAULT_DENSITY):g}, "
            f"seed {int(opts.get('seed', 1))}), {x.shape[1]} steps (SYNTHETIC)")
