"""Lowering a graph to Loihi 1: timing, quantization, a netx-layout HDF5 bundle checked by a bit-exact emulator.

``lower_artefact(graph, options)`` (behind ``target.lower``, ``capabilities.py``) returns a
``LoihiArtefact`` that has already been checked against the IR reference (``checks/exactness.py``).
``options`` is the validated ``LoihiOptions`` record (``options.py``): timing ("exact" | "paper"), scale
("auto" | "global" | "per-layer" | "split" | "fine"), allow_reset_change, source (model path), time_steps
(tSample when the model states no recording length; --time-steps), replicas (K copies: ``replicate.py``;
1 or None: none). ``lower_model``'s ``t_sample`` keyword fixes the sample's length instead (fine-tuning
and the checks lower for the inputs' length).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit import Progress, SnnccError
from snncc.targets.kit.graphs import fold_linear
from snncc.targets.kit.inputs import frame_shape
from snncc.targets.kit.timebase import sample_steps
from snncc.targets.loihi.lowering.timing import lower_timing
from snncc.targets.loihi.lowering.artefact import LoihiArtefact
from snncc.targets.loihi.lowering.chip_units import in_chip_units
from snncc.targets.loihi.lowering.registers import build_network, chain, lif_params_check
from snncc.targets.loihi.lowering.replicate import replicate, replication_note
from snncc.targets.loihi.network import LoihiNetwork
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.mapping.resources import LOIHI1
from snncc.targets.loihi.options import COMPILE_OPTIONS, LoihiOptions

VALIDATION_BATCH = 4
# auto's second look (``scaling.choose``): the paper's rule and its best alternative in argmax agreement with the float
# model on seeded random inputs; as many samples as fit SIGNIFICANCE_WORK synapse-steps of the float reference (the
# float twin), at most SIGNIFICANCE_SAMPLES; fewer than SIGNIFICANCE_MIN cannot tell rules apart (a 95 % interval
# of +-0.12 or more), so a network that large keeps the cheaper rule without the second look (the record says so)
SIGNIFICANCE_SAMPLES, SIGNIFICANCE_MIN = 256, 64
SIGNIFICANCE_WORK = 2.5e10
SIGNIFICANCE_DENSITY, SIGNIFICANCE_SEED = 0.08, 2
VALIDATING = "validating the bundle against the IR reference"


@dataclass
class MeasuredCandidate:
    """A scale candidate's network as ``_lower_model`` measured it: flattened for the kernel, and its run on the
    calibration inputs (``xp``, padded), for ``lower_artefact`` to reuse when it writes the same registers."""

    network: LoihiNetwork
    prepared: Any            # emulator.PreparedNetwork
    xp: np.ndarray
    run: Any                 # its EmulationResult on ``xp``, record "all"


# The candidates the latest ``_lower_model`` measured, kept only for ``lower_artefact`` (``keep_measured``), which takes
# the one with the written bundle's registers (``reuse_measured``) and clears the rest; other callers keep nothing
_MEASURED: list[MeasuredCandidate] = []


def reuse_measured(network: LoihiNetwork) -> MeasuredCandidate | None:
    """The measured candidate whose registers are ``network``'s (``same_registers``: compared, not assumed), its
    prepared kernel rebound to ``network``; None when none is. Empties the list either way."""
    import copy

    from snncc.targets.loihi.network import same_registers

    found = next((m for m in _MEASURED if same_registers(m.network, network)), None)
    _MEASURED.clear()
    if found is None:
        return None
    prepared = copy.copy(found.prepared)
    prepared.network = network
    return MeasuredCandidate(network, prepared, found.xp, found.run)


@dataclass
class LoweredModel:
    """Everything lowering produced, for checks: the graphs at each stage and the network."""

    trained: Graph           # the model as given (its own update order; with --replicas its exact replica)
    order: Graph             # the IR in the order Loihi runs (timing change, reset change)
    quantized: Graph         # ``order`` with quantized parameters read back in float
    layers: list
    network: LoihiNetwork
    quant_record: Any
    timing_record: Any
    deployed: Graph | None = None   # ``trained`` with only the reset change (None: same as ``trained``)
    notes: list[str] = field(default_factory=list)
    calibration_float: dict | None = None   # ``order``'s float spikes on the calibration inputs (None: not run)
    validation_float: tuple | None = None   # (the validation's inputs, ``order``'s float spikes on them)
    twin_structure: str = ""                # ``exactness.twin_structure`` of the network those two ran on


_RECENT: OrderedDict[str, LoweredModel] = OrderedDict()   # graph content + options -> lowering (this process)
RECENT_KEPT = 2
RECENT_MAX_WEIGHTS = 2_000_000     # a graph with more weights is not kept: its copy would double the compile's memory


def content_key(graph: Graph, options: LoihiOptions, t_sample: int | None = None) -> str:
    """SHA-256 of everything lowering reads: the graph (nodes, parameters, edges, dt, metadata) and the
    options it reads (``COMPILE_OPTIONS``, ``t_sample``; ``source`` for a graph that names no source file);
    equal keys lower to equal results (lowering is deterministic: seeded calibration)."""
    import hashlib
    import json

    from snncc.ir.serialize import graph_to_record
    from snncc.targets.kit.inputs import to_jsonable

    read: dict[str, Any] = {**options.compile_record(), "t_sample": t_sample}
    if "source_file" not in graph.metadata:
        read["source"] = options.source          # the bundle records it only then
    record, arrays = graph_to_record(graph)
    h = hashlib.sha256(json.dumps(to_jsonable([record, read]), sort_keys=True).encode())
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}{a.dtype}{a.shape}".encode())
        h.update(a.data if a.size else b"")      # the buffer itself: no copy of a large matrix
    return h.hexdigest()


def lower_model(graph: Graph, options: LoihiOptions, progress: Progress | None = None, *,
                t_sample: int | None = None, keep_measured: bool = False) -> LoweredModel:
    """Timing, quantization and register values (no validation); ``progress(done, total, phase)`` as the
    scale rule's candidates are measured (``--scale auto``). The last ``RECENT_KEPT`` results are kept
    by content (``content_key``), so a check that lowers the model compile just lowered does not redo the
    calibration; the checks compare what they use with the written bundle anyway (``checks/written.py``).
    A graph of more than ``RECENT_MAX_WEIGHTS`` weights is lowered afresh each time (a kept copy of its
    lowering would double the memory a compile needs, and copying it costs what the key saves). ``keep_measured``:
    the scale candidates' measurements stay in ``_MEASURED`` for ``reuse_measured``."""
    import copy

    from snncc.ir.nodes import Dense

    if sum(int(np.size(op.weight)) for _, op in graph.items() if isinstance(op, Dense)) > RECENT_MAX_WEIGHTS:
        return _lower_model(graph, options, progress, t_sample, keep_measured)
    key = content_key(graph, options, t_sample)
    if key in _RECENT:
        _RECENT.move_to_end(key)
        return copy.deepcopy(_RECENT[key])      # a caller may change what it gets; the kept one stays as made
    lowered = _lower_model(graph, options, progress, t_sample, keep_measured)
    _RECENT[key] = copy.deepcopy(lowered)
    while len(_RECENT) > RECENT_KEPT:
        _RECENT.popitem(last=False)
    return lowered


def _lower_model(graph: Graph, options: LoihiOptions, progress: Progress | None = None,
                 t_sample: int | None = None, keep_measured: bool = False) -> LoweredModel:
    from snncc.ir.liveness import calibration_spikes, calibration_text
    from snncc.targets.loihi.lowering import scaling
    from snncc.targets.loihi.checks.exactness import (lead_steps, loihi_spikes, pad, twin_spikes, twin_structure,
                                                      validation_spikes)

    timing_mode = options.timing_mode
    rule = options.scale_rule
    _MEASURED.clear()
    frame = frame_shape(graph)           # the input frame (C, H, W) before convolutions are folded
    graph, fold = fold_linear(graph)     # Conv -> connection matrix; linear chains -> one projection
    copies = 1 if options.replicas is None else int(options.replicas)     # --replicas (replicate.py)
    graph, replication = replicate(graph, copies)
    layers = chain(graph)
    deployed, reset_changes = lif_params_check(graph, layers, bool(options.allow_reset_change))
    order, trec = lower_timing(deployed, timing_mode)   # exact timing returns ``deployed`` itself where it can
    trec.changes = reset_changes + trec.changes
    steps: int | None = t_sample
    if steps is not None:
        t_rule = "the input length"
    else:   # --time-steps, else the recording length, else the default every target uses (kit.timebase)
        steps, t_rule = sample_steps(graph, options.time_steps)
    steps = int(steps)

    names = [c.lif for c in layers]
    calib = calibration_spikes(graph.node(layers[0].pre).width, steps)   # the inputs compile's liveness warning uses
    validation_inputs = validation_spikes(VALIDATION_BATCH, steps, graph.node(layers[0].pre).width)
    reference: dict[str, Any] = {}

    def measure(gq: Graph, rq) -> scaling.CandidateMeasure:
        """Mean over layers of ``count_error`` (per-neuron spike counts against the float model's), whether
        the outputs are silent, and what netx lacks to run the candidate as written."""
        from snncc.targets.kit.agreement import argmax_agreement
        from snncc.targets.loihi.bundle.portability import netx_runnable
        from snncc.targets.loihi.emulation.emulator import PreparedNetwork

        net = build_network(order, layers, rq, trec, steps + trec.output_shift, {})
        lead = lead_steps(trec.shifts, trec.output_shift)
        xp = pad(calib, lead)
        if "spikes" not in reference:
            # the float model in Loihi's order: its float twin (every rule's structure), on the calibration inputs
            # and, in the same run, on the validation's (the bundle's check 1 uses them: one run, not two)
            both = twin_spikes(net, order, layers, np.concatenate([xp, pad(validation_inputs, lead)]), trec.shifts,
                               steps)
            reference["spikes"] = {k: v[:len(calib)] for k, v in both.items()}
            reference["validation"] = (validation_inputs, {k: v[len(calib):] for k, v in both.items()})
            reference["structure"] = twin_structure(net, order, layers)
        prepared = PreparedNetwork(net)
        run = prepared.run(xp, record="all")
        _MEASURED.append(MeasuredCandidate(net, prepared, xp, run))
        emu = loihi_spikes(run, net, layers, trec.shifts, steps)
        float_silent = not reference["spikes"][names[-1]].any()
        error = None if float_silent else float(sum(count_error(emu[n], reference["spikes"][n]) for n in names) / len(names))
        agreement = argmax_agreement(reference["spikes"][names[-1]].sum(axis=1), emu[names[-1]].sum(axis=1))
        return scaling.CandidateMeasure(error, outputs_silent=not emu[names[-1]].any(), float_silent=float_silent,
                                        gaps=netx_runnable(net), agreement=agreement.as_dict())

    def affordable(synapses: int) -> int:
        """Samples of the second look within SIGNIFICANCE_WORK synapse-steps of the float reference."""
        return int(min(SIGNIFICANCE_SAMPLES, SIGNIFICANCE_WORK // max(1, synapses * steps)))

    model_synapses = sum(int(np.count_nonzero(order.node(d).weight)) for c in layers for d in (c.ff, c.rec) if d)
    too_large = None
    if affordable(model_synapses) < SIGNIFICANCE_MIN:
        too_large = (f"{model_synapses:,} synapses x {steps} steps allow {affordable(model_synapses)} sample(s) of the "
                     f"float reference within the compile's budget, and telling rules apart takes at least "
                     f"{SIGNIFICANCE_MIN}")

    def compare(records: dict) -> dict:
        """Argmax agreement of each candidate (records by name) with the float model on the significance set, and
        its cores (the mapper's lower bound)."""
        from snncc.targets.kit.agreement import argmax_agreement, random_inputs
        from snncc.targets.loihi.emulation.emulator import emulate
        from snncc.targets.loihi.mapping.partition import core_lower_bound

        nets = {name: build_network(order, layers, rq, trec, steps + trec.output_shift, {})
                for name, rq in records.items()}
        first = next(iter(nets.values()))
        synapses = sum(int(np.count_nonzero(lay.weight)) + (0 if lay.weight_rec is None else
                                                            int(np.count_nonzero(lay.weight_rec)))
                       for lay in first.layers[1:])
        samples = affordable(synapses)
        if samples < SIGNIFICANCE_MIN:
            return {"samples": 0, "inputs": f"not measured: {synapses:,} synapses x {steps} steps would allow "
                    f"{samples} sample(s) of the float reference within the compile budget (at least "
                    f"{SIGNIFICANCE_MIN} are needed to tell rules apart); `snncc check` measures a bundle on as many "
                    "as it is given", "agreement": {}, "cores": {}}
        x = random_inputs(samples, steps, first.input_width, SIGNIFICANCE_DENSITY, SIGNIFICANCE_SEED)
        xp = pad(x, lead_steps(trec.shifts, trec.output_shift))
        last, s = names[-1], trec.shifts.get(names[-1], 0)
        ref = twin_spikes(first, order, layers, xp, trec.shifts, steps)[last].sum(axis=1, dtype=np.int64)
        agreement, cores = {}, {}
        for name, net in nets.items():
            out = emulate(net, xp).output_spikes[:, s:s + steps, :net.layers[-1].model_n]
            agreement[name] = argmax_agreement(ref, out.sum(axis=1, dtype=np.int64)).as_dict()
            cores[name] = core_lower_bound(net)
        return {"samples": samples, "inputs": f"{samples} seeded random spike trains (density {SIGNIFICANCE_DENSITY}, "
                f"seed {SIGNIFICANCE_SEED}), {steps} steps (SYNTHETIC)", "agreement": agreement, "cores": cores}

    quantized, qrec = scaling.choose(order, rule, measure, calibration_text(steps), progress=progress, compare=compare,
                                     no_second_look=too_large)
    quantized = in_chip_units(quantized, qrec)   # the same spikes; ties at threshold decided as on the chip
    meta = {
        "source_sha256": graph.metadata.get("source_sha256", ""),
        "source_file": graph.metadata.get("source_file", options.source),
        "model_name": graph.name,
        "layer_names": [layers[0].pre] + names,
        "dt": graph.dt,
        "input_copies": graph.metadata.get("input_copies", 1),
        "base_inputs": graph.metadata.get("base_inputs", graph.node(layers[0].pre).width),
        "classes": graph.metadata.get("classes"),
        "update_order": graph.metadata.get("update_order"),
        "timing": timing_mode,
        "output_shift": trec.output_shift,
        "population_shifts": trec.shifts,
        "steps": steps,
        "t_sample_rule": t_rule,
        "input_shape": frame,
        "compile_options": options.compile_record(),
    }
    if replication is not None:
        meta["replication"] = replication
    network = build_network(order, layers, qrec, trec, steps + trec.output_shift, meta)
    if not keep_measured:
        _MEASURED.clear()
    return LoweredModel(graph, order, quantized, layers, network, qrec, trec,
                        deployed=None if deployed is graph else deployed, notes=fold.notes(),
                        calibration_float=reference.get("spikes"), validation_float=reference.get("validation"),
                        twin_structure=reference.get("structure", ""))


def count_error(emulated, reference) -> float:
    """Mean |spike count difference| per neuron and sample, relative to the float model's mean count.

    Counts, not spike-by-spike mismatch: in a recurrent network one moved spike shifts all later
    ones, so spike mismatch saturates and stops telling candidates apart; counts are what the
    readout uses."""
    a, b = emulated.sum(axis=1, dtype=np.int64), reference.sum(axis=1, dtype=np.int64)
    return float(np.abs(a - b).mean() / max(b.mean(), 1.0))


def attach_core_map(network: LoihiNetwork) -> None:
    """Place the network on cores and record the map (refuse maps that would change the network)."""
    core_map = map_network(network)
    if core_map.transforms:
        layer = core_map.transforms[0].get("layer")
        raise SnnccError(
            f"fan-in exceeds the {LOIHI1.input_axons_per_core} input axons of a core; mapping it needs relay neurons that change "
            "the network's timing (see `snncc map` for the relay plan), and compiling a relayed bundle is not supported yet",
            field=f"layer '{layer}'")
    network.core_map = core_map.to_dict()


def lower_artefact(graph: Graph, options: LoihiOptions, progress: Progress | None = None) -> LoihiArtefact:
    """``target.lower``: lower (``lower_model``), place on cores (relays where fan-in needs them) and
    check the bundle against the IR reference (``checks/exactness.py``); ``progress(done, total,
    phase)`` through the scale candidates' measurements and the validation."""
    from snncc.targets.loihi.mapping.relays import needs_relays, relay_agreement, relay_network
    from snncc.targets.loihi.checks.exactness import (lead_steps, pad, twin_structure, validate_lowering,
                                                      validation_spikes)

    lowered = lower_model(graph, options, progress, keep_measured=True)
    notes: list[str] = list(lowered.notes)
    replication = lowered.network.metadata.get("replication")
    if replication is not None:
        notes.append(replication_note(replication))
    network, plan = lowered.network, None
    if needs_relays(lowered.network):
        network, plan = relay_network(lowered.network)   # the mapper's relays: the bundle holds them
    else:
        attach_core_map(lowered.network)
    if progress is not None:
        progress(0, 1, VALIDATING)
    from snncc.targets.loihi.emulation.emulator import PreparedNetwork

    measured = reuse_measured(lowered.network)           # the scale rule's measurement of these registers, if any
    # flattened once: the measurement's, the validation's and liveness' runs
    prepared = measured.prepared if measured is not None else PreparedNetwork(lowered.network)
    same_twin = (lowered.validation_float is not None
                 and lowered.twin_structure == twin_structure(lowered.network, lowered.order, lowered.layers))
    record = validate_lowering(lowered.trained, lowered.order, lowered.quantized, lowered.network, lowered.layers,
                               lowered.timing_record.shifts, lowered.timing_record.output_shift,
                               batch=VALIDATION_BATCH, prepared=prepared,
                               order_twin=lowered.validation_float if same_twin else None)
    validation = record.as_dict()
    if plan is not None:
        trec = lowered.timing_record
        x = validation_spikes(VALIDATION_BATCH, lowered.network.t_sample - trec.output_shift,
                              lowered.network.input_width)
        validation["relays"] = relay_agreement(lowered.network, network, plan,
                                               pad(x, lead_steps(trec.shifts, trec.output_shift)))
        notes += plan.notes()
        notes.append("relayed vs the same bundle without relays (itself checked against the IR above): spike "
                     "agreement " + ", ".join(f"{k} {100 * v:.2f}%" for k, v in
                                              validation["relays"]["spike_agreement"].items())
                     + f"; predictions {100 * validation['relays']['prediction_agreement']:.1f}%"
                     + ("" if plan.exact else " (rate relays are lossy; `snncc check` measures the cost)"))
    # a replicated graph's relays and copies are populations of their own
    liveness = calibration_liveness(lowered.trained if replication is not None else graph, lowered, prepared,
                                    known_run=None if measured is None else (measured.xp, measured.run))
    portability = portability_record(network, lowered.quant_record)
    if progress is not None:
        progress(1, 1, VALIDATING)
    notes.append(f"tSample {network.t_sample}: {lowered.network.metadata['t_sample_rule']}"
                 + (f" + {plan.total_shift} relay step(s)" if plan is not None and plan.total_shift else ""))
    if network.metadata.get("output_shift"):
        notes.append(f"outputs appear {network.metadata['output_shift']} step(s) later than in the IR; tSample "
                     "includes them")
    from snncc.targets.kit.artefact import model_record

    return LoihiArtefact(network=network, quantization=lowered.quant_record.as_dict(),
                         timing=lowered.timing_record.as_dict(), validation=validation, notes=notes,
                         liveness=liveness, portability=portability, model=model_record(graph))


def calibration_liveness(graph: Graph, lowered: LoweredModel, prepared=None,
                         known_run: tuple | None = None) -> dict[str, Any]:
    """Every population's activity on the calibration inputs (``snncc.ir.liveness.calibration_spikes``),
    in float (the model as given) and on Loihi (the lowered network, bit-exact), the silent or saturated
    ones named. (The one-line warning for a model silent in float is compile's: ``calibration_warning``.)
    ``known_run``: (padded inputs, the network's emulation on them, record "all"), used when those inputs are
    these."""
    from snncc.ir import liveness
    from snncc.targets.loihi.checks.exactness import ir_spikes, lead_steps, loihi_spikes, pad, twin_spikes
    from snncc.targets.loihi.emulation.emulator import emulate

    steps = int(lowered.network.metadata["steps"])
    x = liveness.calibration_spikes(lowered.network.input_width, steps)
    names = [c.lif for c in lowered.layers]
    trec, net = lowered.timing_record, lowered.network
    xp = pad(x, lead_steps(trec.shifts, trec.output_shift))
    if lowered.order is lowered.trained and "replication" not in net.metadata:
        # Loihi runs the model's own order: its float spikes are its float twin's (the IR's, as the validation
        # checks spike for spike on every compile), measured with the scale candidates or run here
        floats = lowered.calibration_float
        if floats is None:
            floats = twin_spikes(net, lowered.order, lowered.layers, xp, trec.shifts, steps)
    else:
        floats = ir_spikes(graph, x, names)
    if known_run is not None and np.array_equal(known_run[0], xp):
        run = known_run[1]
    else:
        run = emulate(net, xp, record="all") if prepared is None else prepared.run(xp, record="all")
    chip_run = loihi_spikes(run, net, lowered.layers, trec.shifts, steps)
    f_act = liveness.activity(floats, liveness.graph_refractory(graph))
    l_act = liveness.activity(chip_run, {c.lif: int(net.layers[i].ref_delay) for i, c in enumerate(lowered.layers, 1)})
    return {"inputs": liveness.calibration_text(steps), "float": liveness.as_dicts(f_act),
            "loihi": liveness.as_dicts(l_act),
            "flagged": liveness.flagged(f_act, "in float") + liveness.flagged(l_act, "on Loihi")}


def portability_record(network: LoihiNetwork, quant) -> dict[str, Any]:
    """Whether netx runs the bundle as written (``bundle/portability.py``), why not, and the best bundle
    under a rule netx runs that auto measured beside it."""
    from snncc.targets.loihi.bundle.portability import netx_runnable, portability_line

    gaps = netx_runnable(network)
    calib = quant.calibration or {}
    chosen = calib.get("chosen")
    return {"netx_runnable": not gaps, "line": portability_line(gaps), "reasons": [g.as_dict() for g in gaps],
            "best_netx_rule": calib.get("best_netx_rule"),
            "chosen_error": (calib.get("errors") or {}).get(chosen) if chosen else None,
            "chosen_agreement": calib.get("chosen_agreement"),
            "rule": "netx_runnable (targets/loihi/bundle/portability.py): the rules "
                    "bench/studies/lava_netx_agreement.py measured in lava-dl netx 0.6 + Lava's Loihi 1 fixed-point "
                    "simulation"}


__all__ = ["LoihiArtefact", "LoihiNetwork", "lower_model", "lower_artefact"]
