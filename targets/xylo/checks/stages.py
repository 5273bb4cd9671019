"""``snncc check`` of a Xylo artefact: what the written artefact loses against the float model, and why.

The same inputs run through six stages; each differs from the one before by one cause (``kit.checks.CAUSES``)
and each is compared with the float graph as trained by the one agreement rule (``kit.agreement``):

    trained     the float graph as given                                                   (the reference)
    deployed    the float graph with Xylo's reset by subtraction where the model reset to
                zero (--allow-reset-change; the same run where nothing changed)             -> reset
    decays      deployed, every decay moved to the nearest 1 - 2^-dash (Xylo's decay grid)   -> decays
    uncapped    the artefact's spec.npz as a float IR graph (``lowering/twin.py``): its int8 weights,
                shifts, gains, thresholds, dashes and the rule's placement (direct: several events
                per step where the float model fires one), in float arithmetic, hidden events
                per step not capped                                                         -> weights
    twin        the same with the chip's cap of 31 events per hidden neuron and step        -> saturation
                                                                                               (multi-spike
                                                                                               clipping)
    chip        the artefact in snncc's bit-exact emulator (equal to XyloSim)                 -> saturation
                                                                                               (16-bit saturation
                                                                                               and state rounding)

The chip stage's loss is integer arithmetic: 16-bit saturation of currents and membranes and the rounding of
every decay to a whole number (x >> dash, at least 1). No stage here separates the two (an emulator without
saturation would need a wider kernel), so the stage is attributed to saturation, and the record says so in a
note beside how often the literal emulator saw each lossy rule act on the first ``COUNTED_SAMPLES`` samples
(``details["rule_events"]``). A rule that fires at most once per step by design (single: thresholds above half
the 16-bit range) keeps that cap in ``uncapped`` (lifting it in float arithmetic, where V does not saturate,
would not be the chip), so its multi-spike clipping is 0.

The samples run in chunks (``kit.agreement.chunk_size``): memory does not grow with the sample count; the
float graph runs through ``kit.reference`` (one compute thread), the chip in snncc's emulator. Liveness: every
float population's activity (the model as trained) and the chip's hidden and output neurons'; a population
that never spikes is named (``flagged``), and agreement over silent float outputs is undefined (JSON null).
The float graph's own ceiling: its agreement with itself under ``noise`` weight noise, as
``kit.reference.noise_ceiling`` defines it (``kit.reference.perturbed`` with its seed), chunk by chunk.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF
from snncc.targets.kit.agreement import argmax_agreement, chunk_size, count_correlation
from snncc.targets.kit.checks import CheckReport, accuracy_pair, ceiling_record, report_from, stage
from snncc.targets.xylo.feed import chip_window, read_window

COUNTED_SAMPLES = 8          # samples the literal emulator counts rule events on
UNCAPPED = 1 << 20           # hidden events per step when the chip's cap of 31 is lifted
CHUNK = 64                   # samples per chunk at most
TRIM_EVERY = 8               # chunks between two returns of freed heap memory to the system (``_heap_trimmer``)
POSSIBLE = ("reset", "weights", "decays", "saturation")
STAGES = (
    ("trained", "the float graph as given", None),
    ("deployed", "the float graph as deployed (Xylo's reset by subtraction where it changed)", "reset"),
    ("decays", "deployed, decays on Xylo's 1 - 2^-dash grid", "decays"),
    ("uncapped", "spec.npz in float arithmetic (weights, gains, placement), hidden events per step not capped",
     "weights"),
    ("twin", "spec.npz in float arithmetic with the chip's event caps (multi-spike clipping)", "saturation"),
    ("chip", "spec.npz in snncc's bit-exact emulator (16-bit saturation, state rounding)", "saturation"),
)
CHIP_NOTE = ("the chip stage (integer arithmetic: 16-bit saturation and state rounding, which no stage here "
             "separates) is attributed to saturation; details.rule_events counts how often each acted")


def rounded_decays(graph: Graph) -> Graph:
    """``graph`` with every LIF's decays moved to the nearest Xylo dash (Euler: tau = dt / 2^-dash)."""
    from snncc.targets.xylo.lowering.decays import grid, nearest_dash

    out = graph.copy()
    for _, op in out.items():
        if isinstance(op, LIF):
            a, b = op.decays(out.dt)
            op.discretisation = "euler"
            op.tau_syn = out.dt / np.maximum(1 - grid(nearest_dash(a)), 1e-300)
            op.tau_mem = out.dt / np.maximum(1 - grid(nearest_dash(b)), 1e-300)
    return out


def deployed_graph(graph: Graph, manifest: dict[str, Any]) -> Graph:
    """The float graph as deployed: the reset changes the artefact records applied."""
    if not manifest["quantization"].get("changes"):
        return graph
    out = graph.copy()
    for _, op in out.items():
        if isinstance(op, LIF) and op.reset == "zero":
            op.reset = "subtract"
    return out


def float_counts(graph: Graph, x: np.ndarray) -> np.ndarray:
    """(B, n) readout spike counts of the float graph on ``x`` (``kit.reference.float_counts``)."""
    from snncc.targets.kit.reference import float_counts as counts

    return counts(graph, np.asarray(x))


def twin_graphs(spec) -> tuple[Graph, Graph]:
    """The network spec's float twin (``lowering/twin.py``) with the chip's event caps, and without them (only
    where the twin allows several events: a rule that fires at most once by design keeps its cap)."""
    from snncc.targets.xylo.lowering.twin import HIDDEN_CAP, spec_graph

    twin = spec_graph(spec.kwargs(), float(spec.dt))
    uncapped = twin.copy()
    hidden = uncapped.node("hidden")
    if hidden.max_spikes == HIDDEN_CAP:
        hidden.max_spikes = UNCAPPED
    return twin, uncapped


def twin_counts(twin: Graph, x: np.ndarray, pad: int, lag: int) -> np.ndarray:
    """Output counts of a twin over the model's T steps of ``x`` (fed as the manifest says)."""
    from snncc.targets.kit.reference import float_spikes

    out = float_spikes(twin, chip_window(np.asarray(x), pad, lag), ["output"])["output"]
    return read_window(out, lag, x.shape[1]).sum(axis=1, dtype=np.int64)


def rule_events(written, x: np.ndarray) -> dict[str, int]:
    """How often each lossy rule of the core acted on the first ``COUNTED_SAMPLES`` samples (literal emulator)."""
    from snncc.targets.xylo.emulation.emulator import reference_run

    k = min(COUNTED_SAMPLES, x.shape[0])
    b, t, c = x[:k].shape
    run = np.zeros((k, t + max(written.input_pad, written.output_lag), c), np.uint8)
    run[:, written.input_pad:written.input_pad + t] = np.minimum(x[:k], 255)
    events = reference_run(written.spec, run, count=True).events or {}
    return {"samples": k, **{name: int(v) for name, v in events.items()}}


def random_chunks(samples: int, steps: int, width: int, density: float, seed: int, chunk: int) -> Iterator[np.ndarray]:
    """``kit.agreement.random_inputs(samples, steps, width, density, seed)`` drawn ``chunk`` samples at a time (the
    same spikes: the generator's stream is consumed in the same order)."""
    from snncc.targets.kit import SnnccError

    if not 0.0 < density <= 1.0:
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    rng = np.random.default_rng(seed)
    for start in range(0, samples, chunk):
        yield (rng.random((min(chunk, samples - start), steps, width)) < density).astype(np.uint8)


def given_chunks(x: np.ndarray, chunk: int) -> Iterator[np.ndarray]:
    for start in range(0, x.shape[0], chunk):
        yield x[start:start + chunk]


def chunk_for(graph: Graph, spec, steps: int) -> int:
    """Samples per chunk: the float graph's and the chip's neuron-steps within ``kit.agreement.chunk_size``."""
    from snncc.targets.kit.reference import spiking_neurons

    return chunk_size(max(spiking_neurons(graph), int(spec.n_hidden) + int(spec.n_out)), steps, CHUNK)


def _heap_trimmer() -> Callable[[], object]:
    """A call that hands the C heap's freed pages back to the system (glibc's ``malloc_trim``; elsewhere nothing).

    Each chunk frees what it allocated, but glibc keeps freed medium-sized blocks of the heap, so without this the
    resident size of a long check creeps up with the sample count (measured: 1.12 GB at 10,000 Braille samples,
    0.67 GB at 3,000; with it flat). The kit has no such helper (told the lead): it is kept here until it does."""
    try:
        import ctypes

        trim = ctypes.CDLL("libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return lambda: None
    return lambda: trim(0)


class _Tally:
    """Per-population spike counts over the chunks (liveness), without holding the spikes."""

    def __init__(self) -> None:
        self.counts: dict[str, list[np.ndarray]] = {}
        self.steps = 0

    def add(self, name: str, counts: np.ndarray, steps: int) -> None:
        self.counts.setdefault(name, []).append(np.asarray(counts, np.int64))
        self.steps = int(steps)

    def activity(self, refractory: dict[str, int] | None = None) -> dict[str, Any]:
        from snncc.ir.liveness import activity_from_counts

        refractory = refractory or {}
        return {name: activity_from_counts(np.concatenate(c), self.steps, int(refractory.get(name, 1)))
                for name, c in self.counts.items()}


def check_written(graph: Graph, written, x: np.ndarray | None, labels: np.ndarray | None, inputs: str, *,
                  noise: float | None = None, random: tuple[int, int, float, int] | None = None,
                  artefact: str | None = None, progress: Callable[[int], None] | None = None) -> CheckReport:
    """The stages and losses of the artefact ``written`` (``artefact.read.read_artefact``) on inputs ``x`` (N, T, C)
    or, with ``x`` None, on ``random`` = (samples, steps, density, seed) seeded random spikes drawn chunk by chunk;
    ``labels`` (N,) for accuracy; ``noise``: the float graph's ceiling; ``artefact``: how the record names an
    artefact compiled for the measurement (``kit.measured.described``; None: the caller names it, as the check
    verb does: a path of the artefact is never printed here, a temporary one would no longer exist)."""
    from snncc.ir import liveness
    from snncc.targets.kit.compute import one_thread
    from snncc.targets.kit.reference import float_spikes, perturbed
    from snncc.targets.xylo.emulation.run_artefact import artefact_inputs, emulate_written

    spec, pad, lag = written.spec, written.input_pad, written.output_lag
    if x is not None:
        x = artefact_inputs(x, spec.n_in, None)
        steps = int(x.shape[1])
    else:
        steps = int(random[1])
    chunk = chunk_for(graph, spec, steps)
    chunks = given_chunks(x, chunk) if x is not None else random_chunks(random[0], steps, spec.n_in, random[2],
                                                                         random[3], chunk)
    deployed = deployed_graph(graph, written.manifest)
    decays = rounded_decays(deployed)
    twin, uncapped = twin_graphs(spec)
    readout = [n for n, op in graph.items() if isinstance(op, LIF)][-1]
    counts: dict[str, list[np.ndarray]] = {k: [] for k, _, _ in STAGES}
    noisy: list[np.ndarray] = []
    noisy_graph = perturbed(graph, noise) if noise is not None and noise > 0 else None
    floats, chips = _Tally(), _Tally()
    events: dict[str, int] | None = None
    first: np.ndarray | None = None
    trim, done = _heap_trimmer(), 0
    for part in chunks:
        with one_thread():
            spikes = float_spikes(graph, part)
        for name, s in spikes.items():
            floats.add(name, s.sum(axis=1, dtype=np.int64), s.shape[1])
        counts["trained"].append(spikes[readout].sum(axis=1, dtype=np.int64))
        counts["deployed"].append(counts["trained"][-1] if deployed is graph else float_counts(deployed, part))
        counts["decays"].append(float_counts(decays, part))
        with one_thread():
            counts["uncapped"].append(twin_counts(uncapped, part, pad, lag))
            counts["twin"].append(twin_counts(twin, part, pad, lag))
        run = emulate_written(written, part, record=True)
        counts["chip"].append(run.output_spikes.sum(axis=1, dtype=np.int64))
        chips.add("hidden (chip)", run.states["spikes"].sum(axis=1, dtype=np.int64), run.steps)
        chips.add("output (chip)", counts["chip"][-1], run.steps)
        if noisy_graph is not None:
            noisy.append(float_counts(noisy_graph, part))
        if events is None:
            events = rule_events(written, part)
            first = part
        done += 1
        if done % TRIM_EVERY == 0:
            trim()                              # the chunks' freed memory back to the system: a flat footprint
        if progress is not None:
            progress(int(part.shape[0]))
    c = {k: np.concatenate(v) for k, v in counts.items()}
    samples = int(c["trained"].shape[0])
    lab = None if labels is None else np.asarray(labels).reshape(-1)
    stages = [stage(key, label, cause, argmax_agreement(c["trained"], c[key]),
                    None if lab is None else float(np.mean(np.argmax(c[key], axis=1) == lab)))
              for key, label, cause in STAGES]
    main = argmax_agreement(c["trained"], c["chip"])
    ceiling = None
    if noisy:
        ceiling = ceiling_record(argmax_agreement(c["trained"], np.concatenate(noisy)), noise)
    f_act = floats.activity(liveness.graph_refractory(graph))
    c_act = chips.activity()
    warning = liveness.float_silence_warning(graph, first, f_act, f"the first {first.shape[0]} of these samples") \
        if first is not None else None
    quant = written.manifest["quantization"]
    changes = list(quant.get("changes") or [])
    notes = (["reset change: " + "; ".join(changes)] if changes
             else ["no reset change: the model resets by subtraction"]) + [CHIP_NOTE]
    if x is None:
        notes.append("random spike trains: agreement with the float model, not accuracy on real data")
    events = events or {"samples": 0}
    details = {"chip": written.chip, "rule": quant["rule"], "rule_events": events,
               "feed": {"input_pad": pad, "output_lag": lag}}
    if artefact is not None:
        details["artefact"] = artefact
    lines = [f"Xylo {written.chip}, rule {quant['rule']}; fed {pad} zero step(s) before each sample, outputs read "
             f"{lag} step(s) later",
             f"rule events on the first {events.get('samples', 0)} samples (literal emulator): "
             + ", ".join(f"{k} {v}" for k, v in events.items() if k != "samples")]
    for where, act in (("float", f_act), ("chip", c_act)):     # silent or saturated ones are flagged below
        lines += [f"liveness {where} {name}: {a.text()}" for name, a in act.items() if a.status == "active"]
    return report_from(
        "xylo", inputs=inputs, samples=samples, steps=steps, artefact=main,
        count_correlation=count_correlation(c["chip"], c["trained"]), stages=stages, possible=POSSIBLE,
        accuracy=None if lab is None else accuracy_pair(np.argmax(c["trained"], axis=1),
                                                         np.argmax(c["chip"], axis=1), lab),
        ceiling=ceiling, liveness={"float": liveness.as_dicts(f_act), "chip": liveness.as_dicts(c_act)},
        flagged=liveness.flagged(f_act, "in float") + liveness.flagged(c_act, "on the chip"),
        warnings=[warning] if warning else [], notes=notes, details=details, detail_lines=lines)
