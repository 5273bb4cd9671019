"""The stages both Loihi checks run (``accuracy.py`` with labels, ``agreement.py`` without), on the same inputs.

Each stage differs from the one before it by one cause of loss (``kit.checks.CAUSES``); every stage is
compared with the float graph as trained, (a), on the same samples:

    (r)  ir_reset_changed          the float graph with reset to zero (only when --allow-reset-change
                                   replaced a subtract reset)                                 cause "reset"
    (b)  ir_loihi_order            the IR in the order Loihi runs, float (the paper's export order, say;
                                   only where it differs from the graph before)               cause "timing"
    (c)  ir_quantized              the IR with the quantized weights, thresholds and decays, float
                                   (a fine-tuned bundle: its fine-tuned registers read back)  cause "weights"
    (d') emulator_wide             the bundle's integers with wide registers (no wrap, no clip): decay
                                   truncation and state rounding only                         cause "decays"
    (d0) emulator_without_relays   a relayed bundle's network without its relays              cause "saturation"
    (d)  emulator                  the bundle as written, read from its file, bit-exact       cause "saturation"

(d') -> (d) is what overflow (q and u wraps, v clips) costs; a relayed bundle's (d0) -> (d) is what its
relays cost: a rate relay passes at most one quantum per step and drops the excess at a spike (an event
count capped), so it is counted as saturation too, and the record says so. Copy relays are exact.
(r), (b), (c) exist only inside the compiler: ``written.py`` re-derives them from the model with the
bundle's recorded options; when that does not reproduce the bundle, only (d) is measured, the causes are
undefined and the record says why.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from snncc.ir.graph import Graph
from snncc.targets.kit.agreement import chunk_size
from snncc.targets.kit.compute import one_thread
from snncc.targets.loihi.options import STREAM_GAP

CHUNK = 64
POSSIBLE = ("reset", "weights", "decays", "saturation", "timing")
LABELS = {
    "ir_reset_changed": "(r) float, reset to zero instead",
    "ir_loihi_order": "(b) float, in the order Loihi runs",
    "ir_quantized": "(c) float, quantized parameters",
    "emulator_wide": "(d') the bundle's integers, wide registers (no overflow)",
    "emulator_without_relays": "(d0) the bundle's network without relays, emulated",
    "emulator": "(d) the bundle as written, emulated (bit-exact)",
}
CAUSE_OF = {"ir_reset_changed": "reset", "ir_loihi_order": "timing", "ir_quantized": "weights",
            "emulator_wide": "decays", "emulator_without_relays": "saturation", "emulator": "saturation"}
ORDER = tuple(LABELS)
# per-layer spike agreement: comparison -> (stage, stage it is compared with)
COMPARISONS = {"emulator_vs_trained": ("emulator", "float_trained"),
               "emulator_vs_quantized_ir": ("emulator", "ir_quantized"),
               "loihi_order_vs_trained": ("ir_loihi_order", "float_trained")}
RELAY_NOTE = ("relays: (d0) -> (d) is what the mapper's relays cost (rate relays pass at most one quantum per step "
              "and drop the excess at a spike: counted as saturation; copy relays are exact)")


def float_stages(bundle) -> dict[str, Graph]:
    """The float stages (r), (b), (c) the bundle's re-derived lowering gives, in order (none without one)."""
    lowered = bundle.lowered
    if lowered is None:
        return {}
    out: dict[str, Graph] = {}
    before = lowered.trained
    if lowered.deployed is not None:
        out["ir_reset_changed"] = before = lowered.deployed
    if lowered.order is not before and lowered.order is not lowered.trained:
        out["ir_loihi_order"] = lowered.order
    out["ir_quantized"] = lowered.quantized
    return out


def population_spikes(graph: Graph, x: np.ndarray, names: list[str], cut=None) -> dict[str, np.ndarray]:
    """Per population (B, T, n) uint8 spikes of the float ``graph`` on ``x``; ``cut`` maps a lowering stage's
    populations to the model's neurons (``WrittenBundle.cut``: replicated populations)."""
    from snncc.ir.simulate import simulate   # the float reference: imported where it runs

    with one_thread():
        res = simulate(graph, x, record="spikes", populations=names)
    spikes = {n: np.asarray(res.spikes[n]).astype(np.uint8) for n in names}
    return cut(spikes) if cut is not None else spikes


class _Pairs:
    """Running per-layer spike-entry agreement between two runs (chunks where both are silent left out)."""

    def __init__(self) -> None:
        self.sums: dict[str, list[float]] = {}

    def add(self, a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> None:
        for k in a:
            total = self.sums.setdefault(k, [0.0, 0])
            if a[k].any() or b[k].any():
                total[0] += float(np.mean(a[k] == b[k])) * a[k].shape[0]
                total[1] += a[k].shape[0]

    def shares(self) -> dict[str, float | None]:
        return {k: (s / n if n else None) for k, (s, n) in self.sums.items()}


@dataclass
class Measured:
    """What ``measure`` ran: output counts per stage (``float_trained`` included), per-layer spike agreement per
    comparison, liveness tallies of (a) and (d), overflow of the bundle (or, relayed, of its network without
    relays), and the inputs' sizes."""

    counts: dict[str, np.ndarray]
    spike_agreement: dict[str, dict[str, float | None]]
    float_tally: object
    loihi_tally: object
    overflow: dict[str, int]
    samples: int
    steps: int
    chunk: int
    relayed: bool
    stages: list[str] = field(default_factory=list)     # the stage keys measured, in order

    def prediction(self, key: str) -> np.ndarray:
        return np.argmax(self.counts[key], axis=1)


def measure(graph: Graph, bundle, x_all: np.ndarray, *, mode: str = "batch", gap: int = STREAM_GAP,
            progress: Callable[[int], None] | None = None) -> Measured:
    """Run the float graph, the stages and the bundle on ``x_all`` (N, T, C) 0/1, chunk by chunk (bounded memory);
    ``progress(n)`` after each chunk. ``mode``: the bundle's run ("batch" | "stream" with ``gap`` blank steps)."""
    from snncc.ir import liveness
    from snncc.targets.loihi.checks.exactness import lead_steps, loihi_spikes
    from snncc.targets.loihi.emulation.emulator import emulate, pad

    net = bundle.network
    n, steps, _ = x_all.shape
    names = bundle.populations
    lowered = bundle.lowered
    relayed = lowered is not None and "relayed_layer_index" in net.metadata
    graphs = float_stages(bundle)
    kw = {"mode": "stream", "gap": int(gap)} if mode == "stream" else {}
    counts: dict[str, list[np.ndarray]] = {k: [] for k in ("float_trained", *graphs, "emulator_without_relays",
                                                               "emulator_wide", "emulator")}
    pairs = {k: _Pairs() for k in COMPARISONS}
    overflow = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    float_tally, loihi_tally = liveness.Tally(), liveness.Tally()
    chunk = chunk_size(sum(net.layers[bundle.layer_of[p]].model_n for p in names), steps, CHUNK)
    chunks = []
    for start in range(0, n, chunk):
        x = x_all[start:start + chunk]
        runs = {"float_trained": population_spikes(graph, x, names)}
        for key, g in graphs.items():
            runs[key] = population_spikes(g, x, names, bundle.cut)
        runs["emulator"], res = bundle.run(x, mode=mode, gap=gap)
        over = res.overflow
        if relayed:
            trec = lowered.timing_record
            plain = emulate(lowered.network, pad(x, lead_steps(trec.shifts, trec.output_shift)), record="all", **kw)
            runs["emulator_without_relays"] = bundle.cut(loihi_spikes(plain, lowered.network, lowered.layers,
                                                                      trec.shifts, steps))
            over = plain.overflow
        for k, v in over.items():
            overflow[k] += v
        chunks.append(x)
        for key, spikes in runs.items():
            counts[key].append(spikes[names[-1]].sum(axis=1, dtype=np.int64))
        float_tally.add(runs["float_trained"])
        loihi_tally.add(runs["emulator"])
        runs.setdefault("ir_loihi_order", runs.get("ir_reset_changed", runs["float_trained"]))
        for comp, (got, want) in COMPARISONS.items():
            if got in runs and want in runs and (comp == "emulator_vs_trained" or lowered is not None):
                pairs[comp].add(runs[got], runs[want])
        if progress is not None:
            progress(int(x.shape[0]))
    if lowered is not None:
        base = "emulator_without_relays" if relayed else "emulator"
        if any(overflow.values()):
            for x in chunks:
                if relayed:
                    trec = lowered.timing_record
                    r = emulate(lowered.network, pad(x, lead_steps(trec.shifts, trec.output_shift)), wide=True, **kw)
                    out = r.output_spikes[:, trec.output_shift:trec.output_shift + steps]
                else:
                    out = bundle.run_wide(x, mode=mode, gap=gap)
                counts["emulator_wide"].append(out.sum(axis=1, dtype=np.int64))
        else:
            counts["emulator_wide"] = counts[base]
    found = {k: np.concatenate(v) for k, v in counts.items() if v}
    order = [k for k in ORDER if k in found]
    shares = {comp: p.shares() for comp, p in pairs.items() if p.sums}
    return Measured(found, shares, float_tally, loihi_tally, overflow, n, steps, chunk, relayed, order)


def kit_stages(measured: Measured, labels: np.ndarray | None = None, *, breakdown: bool = True) -> list:
    """The measured stages as ``kit.checks.Stage``s against the float graph as trained (with ``labels``: each
    stage's accuracy too); ``breakdown`` False (stages not re-derived): the bundle alone, with no cause."""
    from snncc.targets.kit.agreement import argmax_agreement
    from snncc.targets.kit.checks import stage

    ref = measured.counts["float_trained"]
    out = []
    for key in measured.stages:
        acc = None if labels is None else float(np.mean(measured.prediction(key) == labels))
        out.append(stage(key, LABELS[key], CAUSE_OF[key] if breakdown else None,
                         argmax_agreement(ref, measured.counts[key]), acc))
    return out


def liveness_fields(graph: Graph, bundle, measured: Measured, x_all: np.ndarray) -> dict:
    """``liveness``, ``flagged`` and ``warnings`` of a ``CheckReport``: every population's activity in float (a)
    and on the bundle (d), and a warning when the float graph is silent on the first chunk of the inputs."""
    from snncc.ir import liveness

    net = bundle.network
    f_act = measured.float_tally.activity(liveness.graph_refractory(graph))
    l_act = measured.loihi_tally.activity({nm: int(net.layers[bundle.layer_of[nm]].ref_delay)
                                           for nm in bundle.populations})
    chunk, n = measured.chunk, measured.samples
    warning = liveness.float_silence_warning(graph, x_all[:chunk], f_act, f"the first {min(chunk, n)} of these samples")
    return {"liveness": {"float": liveness.as_dicts(f_act), "loihi": liveness.as_dicts(l_act)},
            "flagged": liveness.flagged(f_act, "in float") + liveness.flagged(l_act, "on Loihi (the bundle)"),
            "warnings": [warning] if warning else []}


def common_notes(bundle, measured: Measured) -> list[str]:
    """What every Loihi check says about the bundle: the stage breakdown's limits, relays, timing changes, length."""
    notes = []
    if bundle.stages_note:
        notes.append(bundle.stages_note)
    if measured.relayed:
        from snncc.targets.loihi.mapping.relays import RelayPlan

        meta = bundle.network.metadata
        notes += RelayPlan(records=list(meta.get("fan_in_relays") or []), index=list(meta["relayed_layer_index"]),
                           shift=[]).notes()
        notes.append(RELAY_NOTE)
    if measured.steps != bundle.steps:
        notes.append(f"the inputs have {measured.steps} steps; the bundle's tSample is for {bundle.steps} (the emulator "
                     "runs the inputs' length)")
    return notes


def quantization_of(bundle) -> dict:
    """The bundle's quantization record (rule, reason, calibration), or {} where it records none."""
    quant = bundle.network.metadata.get("quantization")
    return quant if isinstance(quant, dict) else {}


def timing_mode(bundle) -> str:
    """The timing the bundle records ("exact", "paper"), else "unknown"."""
    timing = bundle.network.metadata.get("timing")
    if isinstance(timing, str):
        return timing
    return str((timing or {}).get("mode", "unknown")) if isinstance(timing, dict) else "unknown"
