"""The candidates a rule tries (``candidate_rules``) and the network spec one of them gives (``build_candidate``).

A candidate places the hidden populations ``direct`` or ``single`` (a dash pair per population, kernel or
identified weights, optionally with sigma-delta relays) and the readout on the output neurons or on hidden
neurons copied to them. ``lower.py`` measures each in snncc's emulator and keeps the best.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.xylo.chip import XyloChip
from snncc.targets.xylo.lowering import chip_form, decays, regression, sigma_delta
from snncc.targets.xylo.lowering.calibration import Source, own_spikes
from snncc.targets.xylo.lowering.integers import (PopulationRecord, hidden_state_limit, integer_spec,
                                                  output_state_limit)
from snncc.targets.xylo.lowering.relay_plan import PROVISIONAL_SHIFTS, relay_plan, relay_trains, with_relays
from snncc.targets.xylo.lowering.replicas import as_replica, merge_replica_records, replica_events_max, replica_name
from snncc.targets.xylo.lowering.timing import XyloTiming

IDENTIFY_SCALE = 2.0      # regression weight exp(-|V - theta| / (2 theta)) (0.5-4 measured; 2 among the best)
IDENTIFY_RIDGE = 1e-3     # pull towards the kernel fit, relative to the mean curvature
RELAYED_RIDGE = 1e-4      # relayed fits: pull towards zero (1e-3 to 3e-5 measured; 1e-4 among the best)
PAIRS_TRIED = 2


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


def candidate_rules(srcs: list[Source], rule: str, chip: XyloChip, replicas: int = 1,
                    both: bool = False) -> list[Candidate]:
    """The candidates of ``rule`` (``single`` needs two synaptic currents per hidden neuron: not on Xylo IMU;
    ``relayed`` also needs room for its relays, and tries the readout on hidden neurons where they fit, except
    with ``replicas``, whose copies the output neurons read; ``both``: relays at both synapse dashes)."""
    if chip.synapses_per_hidden < 2:
        if rule not in ("auto", "direct"):
            raise SnnccError(f"the {rule} rule needs two synaptic currents per hidden neuron; {chip.name} has "
                             f"{chip.synapses_per_hidden} (use --rule direct)", field="--rule")
        return [Candidate("direct", "direct")]
    fits = [decays.best_pairs(float(np.median(s.alpha)), float(np.median(s.beta)), PAIRS_TRIED) for s in srcs]
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
            room = relay_room(srcs[:-1], pairs, chip, both=both)
            tail = ", relays at both dashes" if both else ""
            if room is None:
                out.append(Candidate(f"relayed dashes {label}{tail}", "single", pairs, True, True, both_dashes=both))
            elif rule == "relayed":
                raise SnnccError(room, field="--rule")
            if replicas == 1 and relay_room(srcs, every, chip, copies=len(srcs[-1].theta), both=both) is None:
                out.append(Candidate(f"relayed dashes {label}{tail}, readout on hidden neurons "
                                     f"(dashes {every[-1][0]},{every[-1][1]}) copied to the output neurons",
                                     "single", every, True, True, "hidden", both))
    return out


def relay_room(hidden: list[Source], pairs: list[tuple[int, int]], chip: XyloChip, copies: int = 0,
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


def build_candidate(srcs: list[Source], n_inputs: int, method: str, pairs: list[tuple[int, int]] | None,
                    identified: bool, chip: XyloChip, timing: XyloTiming | None = None,
                    relayed: bool = False, readout: str = "output",
                    replicas: list[Callable[[], list[Source]]] = (),
                    rounding: str | None = None, both_dashes: bool = False) -> tuple[dict, list[PopulationRecord]]:
    """A spec for one rule: hidden populations ``method`` (single: dash pair per population, kernel or
    identified weights, rounding with error feedback), the readout population on the output neurons
    (``readout`` "output"), or on hidden neurons like the others, copied exactly to the output neurons one
    step later ("hidden": ``integers._copy_readout``; ``pairs`` then has one more entry).
    ``relayed`` (identified single populations only): sigma-delta relays (``sigma_delta.py``) give every hidden
    population a third basis function; their events depend on the matrices' shifts: fitted under
    ``PROVISIONAL_SHIFTS``, and fitted again under the shifts the assembly chose if they differ (then kept).
    Relayed fits are pulled
    towards zero, not towards the two-exponential kernel: its cancelling coefficients (about 7 thresholds
    per unit weight on the Braille RSNN) cost more in int8 rounding than they gain (docs/xylo_lowering.md).
    ``replicas``: more copies of ``srcs``, each calibrated on its own inputs when called (``replicas.replica_sources``;
    fitted one at a time, its traces let go after its fit, calibrated again if the shifts change): every
    hidden population is placed once per copy, fitted and rounded on that copy's inputs (copy k's relays a step
    coarser, ``replica_events_max``), and the readout takes each copy's spikes with 1/K of its weights
    (``readout`` "output" only; ``merge_replica_records`` folds the copies' records into one per population).
    ``rounding``: "none" leaves the weights unrounded (``integer_spec``); else the method's own rounding.
    ``both_dashes``: every relayed source gets relays at both synapse dashes (``relay_plan``)."""
    k_all = 1 + len(replicas)
    if k_all > 1 and readout != "output":
        raise SnnccError("internal check failed: replicas need the readout on the output neurons", field="rule")

    def on_hidden(copy: list[Source]) -> list[Source]:
        return copy if readout == "hidden" else copy[:-1]

    plans = [relay_plan(on_hidden(srcs), pairs, replica_events_max(k), both_dashes) if relayed else []
             for k in range(k_all)]                   # a plan reads only the populations' widths: copy 0's do
    shifts: tuple[int, int] | None = None
    ridge = RELAYED_RIDGE if relayed else IDENTIFY_RIDGE
    for _ in range(2 if plans[0] else 1):
        per_copy, plan, limits = [], [], {}
        for k, copy_plan in enumerate(plans):
            copy = srcs if k == 0 else replicas[k - 1]()
            hid = on_hidden(copy)
            if copy_plan:
                if timing is None:
                    raise SnnccError("internal check failed: a relayed candidate needs the lowering's timing",
                                     field="rule")
                relay_trains(hid, copy_plan, timing, shifts)
            pops = [fit_hidden(s, method, None if pairs is None else pairs[i], identified, copy_plan, ridge)
                    for i, s in enumerate(hid)]
            lims = [hidden_state_limit(p, s.trains, s.v_pre) for p, s in zip(pops, hid)]
            if k_all > 1:
                copy_plan = as_replica(pops, copy_plan, k)
            limits.update({p.name: lim for p, lim in zip(pops, lims)})
            per_copy.append(pops)
            plan += copy_plan
            if k > 0:                              # only copy 0's traces are read again (the readout's fit)
                for s in copy:
                    s.trains, s.raw, s.v_pre = {}, {}, None
        hidden = [pops[i] for i in range(len(per_copy[0])) for pops in per_copy]     # a population's copies adjoin
        if readout == "hidden":
            out, out_limit = None, None
        else:
            out, out_limit = fit_output(srcs[-1], identified, k_all)
        spec, records = integer_spec(hidden, out, n_inputs, srcs[0].pop.pre, limits, out_limit,
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


def _placed(s: Source, method: str, dashes: tuple[int, int] | None) -> chip_form.HiddenFloat:
    srcs = {s.pop.pre: s.w_ff}
    if s.w_rec is not None:
        srcs[s.pop.lif] = s.w_rec
    if method == "direct":
        return chip_form.hidden_direct(s.pop.lif, s.alpha, s.beta, s.theta, srcs, s.bias_v, s.bias_i)
    return chip_form.hidden_single(s.pop.lif, s.alpha, s.beta, s.theta, srcs, dashes, s.bias_v, s.bias_i,
                                   s.bias_lag)


def fit_hidden(s: Source, method: str, dashes: tuple[int, int] | None, identified: bool,
               plan: list[sigma_delta.Relay], ridge: float) -> chip_form.HiddenFloat:
    """One population on hidden neurons, fitted on ``s``'s calibration traces."""
    pop = _placed(s, method, dashes)
    if plan:
        pop = with_relays(pop, s, plan)
    if method == "single":
        if identified:
            return regression.fitted_hidden(pop, s.trains, s.v_pre, IDENTIFY_SCALE, ridge)
        return regression.hidden_hessians(pop, s.trains, s.v_pre, IDENTIFY_SCALE, ridge)
    return pop


def fit_output(last: Source, identified: bool, copies: int) -> tuple[chip_form.OutputFloat, np.ndarray]:
    """The readout population on the output neurons, fitted on ``last``'s traces; with ``copies`` > 1 its
    presynaptic population is placed ``copies`` times (``as_replica`` names): each copy's spikes with 1/copies
    of the weights (the copies' columns are equal, so the fit and the rounding with error feedback share each
    weight among them)."""
    out = chip_form.output_native(last.pop.lif, last.pop.pre, last.alpha, last.beta, last.theta, last.w_ff,
                                  last.bias_v, last.bias_i, bias_source=last.bias_lag == 0)
    pre = last.trains[last.pop.pre]
    if copies > 1:
        n_src = pre.shape[2]
        out.source = replica_name(last.pop.pre, 0)
        out.weight = np.concatenate([out.weight[:, :n_src] / copies] * copies + [out.weight[:, n_src:]], axis=1)
        pre = np.concatenate([pre] * copies, axis=2)
    if out.bias_source:
        pre = np.concatenate([pre, last.trains[chip_form.BIAS_SOURCE]], axis=2)
    if identified:
        out = regression.fitted_output(out, pre, own_spikes(last), last.v_pre, IDENTIFY_SCALE, IDENTIFY_RIDGE)
    return out, output_state_limit(out, pre, last.v_pre)
