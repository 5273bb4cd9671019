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

Lowering, in the IR's terms (``timing.py``, ``chip_form.py``): the graph must be a chain that Xylo can
hold (``structure.py``); subtract reset (a zero reset is refused unless ``allow_reset_change``, then
subtract is deployed and the change recorded); refractory 1; recurrent IR delay 1. Populations run
``timing.shifts`` steps late; the chip is fed ``input_pad`` zero steps before a sample and read from
``output_lag`` on. The rule (``rule``) places hidden populations ``direct`` or ``single``; ``auto``
measures every candidate's argmax agreement with the float graph, the network spec run in snncc's bit-exact
emulator, on calibration inputs (their
second half; the first half fits) and keeps the best (ties: the first listed, the simpler), then fits
the chosen rule again on all of them.

The stages, one module each: ``calibration.py`` (the float graph's traces), ``candidates.py`` (the rules
tried, each a spec), ``relay_plan.py`` / ``sigma_delta.py`` (relays), ``replicas.py`` (``--replicas``),
``regression.py`` (weights fitted to the float graph's voltages), ``integers.py`` (gains, shifts, rounding),
``design_rules.py`` (what the chip holds); this module runs them and describes the result (``XyloLowered``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit import SnnccError
from snncc.targets.kit.graphs import change_reset, fold_linear
from snncc.targets.kit.timebase import sample_steps
from snncc.targets.xylo.chip import CHIPS, get_chip
from snncc.targets.kit.agreement import ArgmaxAgreement, argmax_agreement, count_correlation
from snncc.targets.xylo.feed import chip_window, read_window
from snncc.targets.xylo.lowering import design_rules
from snncc.targets.xylo.lowering.calibration import (Source, calibrate, calibration_inputs, describe, float_counts,
                                                     sources)
from snncc.targets.xylo.lowering.candidates import build_candidate, candidate_rules
from snncc.targets.xylo.lowering.integers import PopulationRecord
from snncc.targets.xylo.lowering.regression import remembered
from snncc.targets.xylo.lowering.replicas import describe_replicas, replica_room, replica_sources
from snncc.targets.xylo.lowering.structure import Population, populations
from snncc.targets.xylo.lowering.timing import XyloTiming, solve_timing
from snncc.targets.xylo.lowering.twin import spec_graph
from snncc.targets.xylo.options import NO_KNOBS, XyloOptions, XyloStudyKnobs


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
    steps: int = 0                       # steps of a sample (the time base), the calibration's
    steps_rule: str = ""                 # the rule that gave them (kit.timebase.sample_steps)

    @property
    def xylo_spec(self):
        """The network spec as an ``XyloSpec`` (checked; ``save_npz`` writes spec.npz)."""
        from snncc.targets.xylo.spec import XyloSpec

        return XyloSpec(**self.spec)

    def chip_input(self, x: np.ndarray) -> np.ndarray:
        """IR inputs (B, T, C) as the chip must be fed (``input_pad`` zero steps before, enough after)."""
        return chip_window(np.asarray(x), self.timing.input_pad, self.timing.output_lag)

    def read_output(self, chip_out: np.ndarray, steps: int) -> np.ndarray:
        return read_window(np.asarray(chip_out), self.timing.output_lag, steps)

    def record(self) -> dict[str, Any]:
        """The quantization record (JSON-able)."""
        return {"chip": self.chip, "dt": self.dt, "rule": self.rule, "timing": self.timing.as_dict(),
                "populations": [p.as_dict() for p in self.populations], "candidates": self.candidates,
                "changes": list(self.changes), "notes": list(self.notes), "calibration": dict(self.calibration),
                "real_time": dict(self.real_time)}


def check_spike_rules(graph: Graph, pops: list[Population]) -> None:
    for p in pops:
        op = graph.node(p.lif)
        if not op.standard_spikes:
            raise SnnccError("the Xylo lowering takes models with the standard spike rule (one spike per step on "
                             f"V > threshold); this population has max_spikes {op.max_spikes}, fire_test "
                             f"'{op.fire_test}'", field=f"node '{p.lif}'")
        if np.any(~np.isfinite(op.threshold)):
            raise SnnccError("a non-spiking population (threshold +inf) cannot run on Xylo's spiking neurons",
                             field=f"node '{p.lif}'.threshold")


def deployed_reset(graph: Graph, pops: list[Population], allow: bool) -> tuple[Graph, list[str]]:
    """The graph with Xylo's reset (subtraction) where the model resets to zero, when ``allow``; else refused."""
    return change_reset(graph, [p.lif for p in pops], from_="zero", to="subtract", allow=allow,
                        refusal="Xylo resets by subtracting the threshold and cannot reset to zero; pass "
                                "--allow-reset-change to deploy reset by subtraction (snncc check measures the cost)",
                        why="Xylo subtracts the threshold")


def twin_counts(twin: Graph, timing: XyloTiming, x: np.ndarray) -> np.ndarray:
    """Output spike counts of the network spec's float twin over the IR's T steps of ``x``."""
    from snncc.ir.simulate import simulate
    from snncc.targets.kit.compute import one_thread

    chip_x = chip_window(np.asarray(x), timing.input_pad, timing.output_lag)
    with one_thread():
        out = np.asarray(simulate(twin, chip_x, record="spikes", populations=["output"]).spikes["output"])
    return read_window(out, timing.output_lag, x.shape[1]).sum(axis=1)


def emulated_output(spec: dict, chip_x: np.ndarray) -> np.ndarray:
    """Output spikes of ``spec`` in snncc's bit-exact emulator (``emulation/emulator.py``)."""
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.spec import XyloSpec

    return emulate(XyloSpec(**spec), chip_x).output_spikes


def _checked(options: XyloOptions, knobs: XyloStudyKnobs):
    """The chip of ``options``; the knobs' rounding checked."""
    try:
        chip = get_chip(options.chip_key)
    except KeyError:
        raise SnnccError(f"chip must be one of {', '.join(CHIPS)}", field="--chip") from None
    if knobs.rounding not in (None, "none"):
        raise SnnccError("rounding must be 'none' or left out", field="rounding")
    if knobs.rounding == "none" and knobs.emulator is None:
        raise SnnccError("an unrounded spec needs an emulator that runs float weights (the twin)", field="rounding")
    return chip


def lower(graph: Graph, options: XyloOptions | None = None, knobs: XyloStudyKnobs = NO_KNOBS) -> XyloLowered:
    """Lower ``graph`` for a Xylo chip: ``options`` the validated option record (``XyloOptions``: chip, rule,
    replicas, relays, allow_reset_change, time_steps, calibration_samples, seed); ``knobs`` what only studies
    set (``XyloStudyKnobs``: given calibration inputs, their density, another emulator for the candidates, an
    unrounded spec). The numerical libraries' thread pools run on one thread meanwhile (``kit.compute.one_thread``:
    the lowering's products are many and medium-sized, and idle pool threads would spin); the emulator spreads
    large batches over its own threads, each doing a share of the samples."""
    from snncc.targets.kit.compute import one_thread

    with one_thread():
        return _lower(graph, options or XyloOptions(), knobs)


def _lower(graph: Graph, options: XyloOptions, knobs: XyloStudyKnobs) -> XyloLowered:
    chip = _checked(options, knobs)
    rule, replicas, both = options.placement_rule, options.copies, options.both_relays
    unrounded = knobs.rounding == "none"

    trained = graph
    g, fold = fold_linear(graph)
    pops = populations(g)
    check_spike_rules(g, pops)
    ref, changes = deployed_reset(g, pops, bool(options.allow_reset_change))
    design_rules.check_graph(ref, pops, chip)
    timing = solve_timing(ref, pops)
    srcs = sources(ref, pops, timing)
    n_in = ref.node(pops[0].pre).width
    steps, steps_rule = sample_steps(graph, options.time_steps)       # the one time base (kit.timebase)
    x = calibration_inputs(options, knobs, n_in, steps)
    half = max(1, x.shape[0] // 2)
    fit_x, sel_x = x[:half], x[half:] if x.shape[0] > 1 else x
    calibrate(ref, srcs, fit_x)
    float_sel = float_counts(ref, sel_x, pops[-1].lif)
    candidates: dict[str, dict[str, Any]] = {}
    emulator = knobs.emulator       # (spec, chip inputs (B, T', C)) -> output spikes (B, T', Nout); None: snncc's
    best = None
    readout_timing = {"output": timing, "hidden": solve_timing(ref, pops, readout_extra=1)}

    def selection_agreement(spec: dict, at: XyloTiming) -> tuple[ArgmaxAgreement, dict[str, Any]]:
        """``spec`` run on the selection half (the given emulator, else snncc's), against the float graph: the
        agreement and its record (``kit.agreement``'s figures and the count correlation)."""
        chip_x = chip_window(sel_x, at.input_pad, at.output_lag)
        out = emulator(spec, chip_x) if emulator is not None else emulated_output(spec, chip_x)
        counts = read_window(np.asarray(out), at.output_lag, sel_x.shape[1]).sum(axis=1)
        agr = argmax_agreement(float_sel, counts)
        return agr, {**agr.as_dict(), "count_correlation": count_correlation(counts, float_sel)}

    with remembered():                  # candidates that fit the same regression share it
        for cand in candidate_rules(srcs, rule, chip, replicas, both):
            if knobs.readout is not None and cand.readout != knobs.readout:
                continue
            ctiming = readout_timing[cand.readout]
            spec, records = build_candidate(srcs, n_in, cand.method, cand.pairs, cand.identified, chip, ctiming,
                                            cand.relayed, cand.readout, rounding=knobs.rounding,
                                            both_dashes=cand.both_dashes)
            spec["dt"] = float(ref.dt)
            agr, candidates[cand.name] = selection_agreement(spec, ctiming)
            if best is None or _better(agr, best[0]):
                best = (agr, cand, spec, records)
    agr, chosen, spec, records = best
    name, timing = chosen.name, readout_timing[chosen.readout]
    if replicas > 1 or (x.shape[0] > 1 and knobs.refit):
        # the chosen rule, fitted again on every calibration sample (the selection half too); replicas: each
        # further copy on its own inputs
        room = replica_room(spec, replicas, chip)
        if room:
            raise SnnccError(room, field="--replicas")
        calibrate(ref, srcs, x)
        extra = replica_sources(ref, srcs, options, knobs, x, replicas)
        spec, records = build_candidate(srcs, n_in, chosen.method, chosen.pairs, chosen.identified, chip, timing,
                                        chosen.relayed, chosen.readout, extra, rounding=knobs.rounding,
                                        both_dashes=chosen.both_dashes)
        spec["dt"] = float(ref.dt)
        if replicas > 1:
            name = f"{name}, {replicas} replicas"
            candidates[name] = dict(selection_agreement(spec, timing)[1],
                                    note="the selection half is among this spec's calibration inputs")
    twin = spec_graph(spec, ref.dt)
    notes = list(timing.notes) + fold.notes()
    real_time: dict[str, Any] = {"note": "not estimated: the weights are unrounded (a measurement, not a spec)"}
    if not unrounded:
        from snncc.targets.xylo.estimate.real_time import event_rates, real_time as estimate_real_time

        design_rules.check_spec(spec, chip)
        rates = event_rates(spec, chip_window(x, timing.input_pad, timing.output_lag))
        rt = estimate_real_time(spec, float(ref.dt), rates)
        notes.append("real time " + rt.line("the calibration inputs"))
        real_time = rt.as_dict()
    notes += bias_notes(srcs, records, timing)
    if any(r.method == "direct" for r in records):
        notes.append("direct rule: a hidden neuron fires up to 31 spikes per step on the chip where the IR fires one "
                     "(the deployed graph states it: max_spikes 31, fire_test '>=')")
    return XyloLowered(spec=spec, chip=chip.key, dt=float(ref.dt), rule=name, timing=timing, populations=records,
                       trained=trained, reference=ref, twin=twin, candidates=candidates, changes=changes, notes=notes,
                       steps=int(x.shape[1]), steps_rule=steps_rule if knobs.calibration is None else "the given inputs",
                       calibration={"inputs": describe(options, knobs, x), "fit_samples": int(fit_x.shape[0]),
                                    "selection_samples": int(sel_x.shape[0]), "metric": "argmax agreement with the "
                                    "float graph over its decided samples (kit.agreement), of the network spec run in "
                                    + ("the given emulator" if emulator is not None else "snncc's bit-exact emulator"),
                                    **({"replicas": replicas, "replica_inputs": describe_replicas(options, knobs)}
                                       if replicas > 1 else {})},
                       real_time=real_time)


def _better(agr: ArgmaxAgreement, best: ArgmaxAgreement) -> bool:
    """A candidate beats the best so far when its agreement is higher (an undefined one never beats; ties keep the
    first listed, the simpler)."""
    return agr.share is not None and (best.share is None or agr.share > best.share)


def bias_notes(srcs: list[Source], records: list[PopulationRecord], timing: XyloTiming) -> list[str]:
    """What the chip makes of each population's biases (exact, or how it differs)."""
    out = []
    method = {r.name: r.method for r in records}
    for k, s in enumerate(srcs):
        if not (np.any(s.bias_v) or np.any(s.bias_i)):
            continue
        name, late = s.pop.lif, timing.shifts[s.pop.lif]
        if k < len(srcs) - 1 and method[name] == "single" and s.bias_lag is not None:
            out.append(f"{name}: biases carried by its bias register (step 0) and the always-on source neuron "
                       "(from step 1): exact up to the kernel fit")
        elif k == len(srcs) - 1 and s.bias_lag == 0:
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
