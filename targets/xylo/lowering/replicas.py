"""``--replicas K``: K copies of the hidden network, each fitted and rounded on its own calibration inputs, read
by the output neurons with 1/K of the weights (docs/xylo_lowering.md, "Replicas").

    replica_sources(...)       copies 1 .. K-1 of the calibration, each on its own inputs
    replica_name / as_replica  the names a copy's populations and relays take inside the network spec
    replica_events_max(k)      copy k's relays a step coarser (their quantization errors differ)
    merge_replica_records      one record per population over its copies
    replica_room(spec, K)      whether K copies fit the chip (one line why not)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.xylo.chip import XyloChip
from snncc.targets.xylo.lowering import sigma_delta
from snncc.targets.xylo.lowering.calibration import Source, calibrate, calibration_inputs
from snncc.targets.xylo.lowering.chip_form import SINGLE_THRESHOLD, HiddenFloat
from snncc.targets.xylo.lowering.integers import PopulationRecord
from snncc.targets.xylo.options import XyloOptions, XyloStudyKnobs

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
    return max(sigma_delta.EVENTS_MAX - REPLICA_EVENTS_STEP * k, REPLICA_EVENTS_MIN)


def as_replica(pops: list[HiddenFloat], plan: list[sigma_delta.Relay], k: int) -> list[sigma_delta.Relay]:
    """Rename copy ``k``'s populations, the sources they read and their relays (``replica_name``; the input and the
    bias source stay shared), in place; returns copy k's relays under their new names."""
    names = {p.name: replica_name(p.name, k) for p in pops}
    renamed = dict(names)
    out = []
    for r in plan:
        source = names.get(r.source, r.source)
        new = sigma_delta.Relay(source, r.n, r.dash, r.events_max, tag="" if source != r.source else f"#{k}",
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


def replica_room(spec: dict[str, Any], replicas: int, chip: XyloChip) -> str | None:
    """None when ``replicas`` copies of ``spec``'s hidden neurons (the bias source shared) fit ``chip``, else why
    not, in one line."""
    if replicas == 1:
        return None
    n = int(np.asarray(spec["threshold"]).size)
    bias_source = int(has_bias_source(spec))
    total = replicas * (n - bias_source) + bias_source
    if total > min(chip.max_hidden, chip.max_input_expansion, chip.max_output_expansion):
        return (f"{replicas} replicas need {total:,} hidden neurons ({n - bias_source} each"
                f"{' and the bias source' if bias_source else ''}); {chip.name} has {chip.max_hidden:,}"
                + ("" if chip.max_input_expansion >= total and chip.max_output_expansion >= total else
                   f" and lets input weights reach {chip.max_input_expansion} and output weights leave "
                   f"{chip.max_output_expansion}"))
    return None


def has_bias_source(spec: dict[str, Any]) -> bool:
    """Whether the last hidden neuron is the always-on bias source (no input, memoryless, V = bias = threshold)."""
    k = int(np.asarray(spec["threshold"]).size) - 1
    return bool(k >= 0 and not np.any(spec["weights_in"][:, k]) and not np.any(spec["weights_rec"][:, k])
                and int(spec["dash_mem"][k]) == 0 and int(spec["bias"][k]) == int(spec["threshold"][k])
                == SINGLE_THRESHOLD)


def replica_seed(options: XyloOptions, k: int) -> int:
    """The seed of copy ``k``'s calibration inputs."""
    return int(options.seed) + k * REPLICA_SEED_STRIDE


def replica_sources(ref: Graph, srcs: list[Source], options: XyloOptions, knobs: XyloStudyKnobs, x: np.ndarray,
                    replicas: int) -> list[Callable[[], list[Source]]]:
    """Copies 1 .. replicas-1 of ``srcs``, each calibrated on its own inputs when asked for (a call each: the
    lowering fits one copy at a time and lets its traces go, so memory holds one copy's calibration beside copy
    0's): seeded random inputs of seed ``seed + k * REPLICA_SEED_STRIDE`` (as the calibration inputs), or, for
    given inputs, a seeded resample of them with replacement. A copy calibrated again is the same copy."""
    def copy(k: int) -> Callable[[], list[Source]]:
        def calibrated() -> list[Source]:
            if knobs.calibration is not None:
                rng = np.random.default_rng(replica_seed(options, k))
                xk = x[rng.integers(0, x.shape[0], x.shape[0])]
            else:
                xk = calibration_inputs(options, knobs, x.shape[2], x.shape[1], seed=replica_seed(options, k))
            out = [replace(s, trains={}, raw={}, v_pre=None) for s in srcs]
            calibrate(ref, out, xk)
            return out

        return calibrated

    return [copy(k) for k in range(1, replicas)]


def describe_replicas(options: XyloOptions, knobs: XyloStudyKnobs) -> str:
    """How each copy's calibration inputs and relays came about (the artefact's record)."""
    how = ("a seeded resample (with replacement) of the given spike trains, seed"
           if knobs.calibration is not None else "seeded random spike trains as copy 0's, seed")
    return (f"copy 0: the calibration inputs; copy k: {how} {int(options.seed)} + {REPLICA_SEED_STRIDE} k; copy k's "
            f"relays at most {sigma_delta.EVENTS_MAX} - {REPLICA_EVENTS_STEP} k events a step (at least "
            f"{REPLICA_EVENTS_MIN})")
