"""``snncc check`` of a Xylo artefact: what the written artefact loses against the float model, and why.

The same inputs run through five stages; each differs from the one before by one cause:

    trained     the float graph as given
    deployed    the float graph as deployed: reset by subtraction where the model reset to zero
                (Xylo's only reset; --allow-reset-change)                              -> reset change
    decays      the deployed float graph with every decay moved to the nearest 1 - 2^-dash
                (Xylo's decay grid, nothing else changed)                              -> decay rounding
    uncapped    the artefact's spec.npz as a float IR graph (twin.py): its int8 weights, shifts, gains,
                thresholds, dashes and the rule's placement (direct: several events per step where the
                float model fires one), in float arithmetic, hidden events per step not capped
                                                                                       -> weight quantization and
                                                                                          the rule's placement
    twin        the same with the chip's cap of 31 events per hidden neuron and step   -> multi-spike clipping
    chip        the artefact in snncc's bit-exact emulator (equal to XyloSim)          -> integer arithmetic:
                                                                                          16-bit saturation,
                                                                                          state rounding

Each stage's argmax agreement with ``deployed`` (``trained`` for the reset change) is measured over the
samples whose reference output has one clear winner (the others counted beside), with its 95 % Wilson
interval; with labels also its accuracy. A cause's loss is the drop from the stage before (stages are
successive, so the losses are not independent and may be negative where a later stage compensates).
A rule that fires at most once per step by design (single: thresholds above half the 16-bit range)
keeps that cap in ``uncapped`` (lifting it in float arithmetic, where V does not saturate, would not
be the chip), so its multi-spike clipping is 0. How often each lossy rule of the core acted is counted by the literal emulator
(``emulator.reference_run(count=True)``) on the first samples: current and membrane saturations,
hidden and output neuron-steps whose events were clipped at the cap (31, 1), inputs clipped at 15.
Liveness (``snncc.ir.liveness``): every float population's activity, and the chip's hidden and output
neurons' in the emulator; a model silent in float is said in one line.
"""

from __future__ import annotations

import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snncc.ir.graph import Graph
from snncc.ir.nodes import LIF, Dense
from snncc.targets.xylo import feed as measure

COUNTED_SAMPLES = 8          # samples the literal emulator counts rule events on
STAGES = ("trained", "deployed", "decays", "uncapped", "twin", "chip")
CAUSES = {"deployed": "reset change", "decays": "decay rounding",
          "uncapped": "weight quantization and the rule's placement",
          "twin": "multi-spike clipping (31 events per hidden neuron and step)",
          "chip": "integer arithmetic (16-bit saturation, state rounding)"}
UNCAPPED = 1 << 20           # hidden events per step when the chip's cap of 31 is lifted


def _last_lif(graph: Graph) -> str:
    return [n for n, op in graph.items() if isinstance(op, LIF)][-1]


def float_counts(graph: Graph, x: np.ndarray) -> np.ndarray:
    from snncc.ir.simulate import simulate
    from snncc.targets.kit.compute import one_thread

    with one_thread():
        return simulate(graph, np.asarray(x), record="spikes").spikes[_last_lif(graph)].numpy().sum(axis=1)


def rounded_decays(graph: Graph) -> Graph:
    """``graph`` with every LIF's decays moved to the nearest Xylo dash (Euler: tau = dt / 2^-dash)."""
    from snncc.targets.xylo.lowering import decays as kernels

    out = graph.copy()
    for _, op in out.items():
        if isinstance(op, LIF):
            a, b = op.decays(out.dt)
            op.discretisation = "euler"
            op.tau_syn = out.dt / np.maximum(1 - kernels.grid(kernels.nearest_dash(a)), 1e-300)
            op.tau_mem = out.dt / np.maximum(1 - kernels.grid(kernels.nearest_dash(b)), 1e-300)
    return out


def perturbed(graph: Graph, noise: float, seed: int) -> Graph:
    """``graph`` with every Dense weight times (1 + noise * N(0, 1)) (the float model's own sensitivity)."""
    rng = np.random.default_rng(seed)
    out = graph.copy()
    for _, op in out.items():
        if isinstance(op, Dense):
            op.weight = op.weight * (1 + noise * rng.standard_normal(op.weight.shape))
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


def twin_counts(spec, x: np.ndarray, pad: int, lag: int, capped: bool = True) -> np.ndarray:
    """Output counts of the network spec's float twin (``twin.py``); ``capped`` False: its hidden neurons may fire any
    number of events per step (only where the twin allows several: a rule that fires at most once by design
    keeps its cap, which then clips nothing the chip would not)."""
    from snncc.ir.simulate import simulate
    from snncc.targets.xylo.lowering.twin import HIDDEN_CAP, spec_graph
    from snncc.targets.kit.compute import one_thread

    twin = spec_graph(spec.kwargs(), float(spec.dt))
    hidden = twin.node("hidden")
    if not capped and hidden.max_spikes == HIDDEN_CAP:
        hidden.max_spikes = UNCAPPED
    with one_thread():
        out = simulate(twin, measure.chip_window(np.asarray(x), pad, lag), record="spikes").spikes["output"].numpy()
    return measure.read_window(out, lag, x.shape[1]).sum(axis=1)


def chip_run(written, x: np.ndarray):
    """The artefact on ``x`` in snncc's emulator, states recorded (``run_artefact.XyloEmulation``)."""
    from snncc.targets.xylo.emulation.run_artefact import emulate_written

    return emulate_written(written, x, record=True)


def chip_liveness(run) -> dict[str, Any]:
    """Activity of the chip's hidden and output neurons (``snncc.ir.liveness``; hidden counts may exceed 1 per step)."""
    from snncc.ir.liveness import activity_from_counts

    steps = run.steps
    return {"hidden (chip)": activity_from_counts(run.states["spikes"].sum(axis=1, dtype=np.int64), steps).as_dict(),
            "output (chip)": activity_from_counts(run.output_spikes.sum(axis=1, dtype=np.int64), steps).as_dict()}


def rule_events(written, x: np.ndarray) -> dict[str, int]:
    """How often each lossy rule of the core acted on the first ``COUNTED_SAMPLES`` samples (literal emulator)."""
    from snncc.targets.xylo.emulation.emulator import reference_run

    k = min(COUNTED_SAMPLES, x.shape[0])
    b, t, c = x[:k].shape
    run = np.zeros((k, t + max(written.input_pad, written.output_lag), c), np.uint8)
    run[:, written.input_pad:written.input_pad + t] = np.minimum(x[:k], 255)
    events = reference_run(written.spec, run, count=True).events or {}
    return {"samples": k, **{name: int(v) for name, v in events.items()}}


@dataclass
class Stage:
    name: str
    what: str
    agreement: dict[str, Any]          # with the reference (measure.Agreement.as_dict())
    reference: str
    accuracy: float | None = None      # with labels


@dataclass
class XyloCheckRecord:
    """What the written artefact loses against the float model, stage by stage, and why (module doc)."""

    artefact_path: str
    chip: str
    rule: str
    inputs: str
    samples: int
    steps: int
    stages: list[Stage]
    losses: list[dict[str, Any]]
    events: dict[str, int]
    overall: dict[str, Any]            # the chip against the float graph as trained
    ceiling: dict[str, Any] | None = None
    liveness: dict[str, Any] = field(default_factory=dict)   # float populations and chip neurons: activity
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def render_text(self, console) -> None:
        console.print(f"Xylo artefact {self.artefact_path} ({self.chip}, rule {self.rule}) on {self.inputs}", markup=False,
                      soft_wrap=True)
        for s in self.stages:
            a = measure.Agreement(**{k: s.agreement[k] for k in measure.Agreement.__dataclass_fields__})
            acc = "" if s.accuracy is None else f"; accuracy {100 * s.accuracy:.1f} %"
            console.print(f"  {s.name:9s} vs {s.reference:8s}: {a.line()}{acc}", markup=False, soft_wrap=True)
        console.print("loss by cause (agreement points; successive stages, not independent):", markup=False)
        for row in self.losses:
            extra = "" if row.get("accuracy_points") is None else f", accuracy {row['accuracy_points']:+.1f} points"
            console.print(f"  {row['cause']}: {row['agreement_points']:+.1f}{extra}", markup=False, soft_wrap=True)
        ev = ", ".join(f"{k} {v}" for k, v in self.events.items() if k != "samples")
        console.print(f"rule events on the first {self.events.get('samples', 0)} samples: {ev}", markup=False,
                      soft_wrap=True)
        a = self.overall
        console.print(f"artefact vs the float graph as trained: {a['agreement']:.3f} [{a['low']:.3f}, {a['high']:.3f}] "
                      f"over {a['counted']} clear-winner samples", markup=False)
        if self.ceiling:
            console.print(f"ceiling: the float graph against itself under {self.ceiling['noise']:g} weight noise: "
                          f"{self.ceiling['agreement']:.3f}", markup=False)
        for where, pops in self.liveness.items():
            for name, a in pops.items():
                console.print(f"liveness {where} {name}: {a['status']}, {a['spikes']} spikes ({a['rate']:.4f} per "
                              f"neuron and step), {a['silent_neurons']}/{a['neurons']} neurons silent", markup=False,
                              soft_wrap=True)
        for note in self.notes:
            console.print(f"note: {note}", markup=False, soft_wrap=True)


def check_written(graph: Graph, written, x: np.ndarray, labels: np.ndarray | None, inputs: str,
                  noise: float | None = None) -> XyloCheckRecord:
    """The stages and losses of the artefact ``written`` (``written.read_artefact``) on inputs ``x`` (N, T, C)."""
    from snncc.targets.xylo.emulation.run_artefact import artefact_inputs as _inputs

    from snncc.ir import liveness

    x = _inputs(x, written.spec.n_in, None)
    deployed = deployed_graph(graph, written.manifest)
    run = chip_run(written, x)
    counts = {"trained": float_counts(graph, x),
              "deployed": float_counts(deployed, x) if deployed is not graph else None,
              "decays": float_counts(rounded_decays(deployed), x),
              "uncapped": twin_counts(written.spec, x, written.input_pad, written.output_lag, capped=False),
              "twin": twin_counts(written.spec, x, written.input_pad, written.output_lag),
              "chip": run.output_spikes.sum(axis=1, dtype=np.int64)}
    if counts["deployed"] is None:
        counts["deployed"] = counts["trained"]
    what = {"trained": "the float graph as given", "deployed": "the float graph as deployed (reset changes applied)",
            "decays": "deployed, decays on Xylo's 1 - 2^-dash grid",
            "uncapped": "spec.npz in float arithmetic, hidden events per step not capped",
            "twin": "spec.npz in float arithmetic with the chip's event caps",
            "chip": "spec.npz in snncc's bit-exact emulator"}
    stages, previous = [], None
    losses = []
    for name in STAGES:
        ref = "trained" if name in ("trained", "deployed") else "deployed"
        agr = measure.agreement(counts[name], counts[ref]).as_dict()
        acc = None if labels is None else float(np.mean(np.argmax(counts[name], axis=1) == labels))
        stages.append(Stage(name, what[name], agr, ref, acc))
        if name in CAUSES:
            base_agr = 1.0 if name in ("deployed", "decays") else previous.agreement["agreement"]
            row = {"cause": CAUSES[name], "stage": name,
                   "agreement_points": 100.0 * (base_agr - agr["agreement"]),
                   "accuracy_points": None if acc is None or previous is None or previous.accuracy is None
                   else 100.0 * (previous.accuracy - acc)}
            losses.append(row)
        previous = stages[-1]
    events = rule_events(written, x)
    overall = measure.agreement(counts["chip"], counts["trained"]).as_dict()
    ceiling = None
    if noise is not None and noise > 0:
        draws = [measure.agreement(float_counts(perturbed(deployed, noise, 100 + k), x), counts["deployed"]).agreement
                 for k in range(3)]
        ceiling = {"noise": noise, "agreement": float(np.mean(draws)), "draws": draws}
    activity = liveness.population_activity(deployed, np.asarray(x, np.float32))
    alive = {"float (deployed)": liveness.as_dicts(activity), "chip": chip_liveness(run)}
    silent = liveness.silence_warning(deployed, activity, inputs, int(x.shape[1]))
    notes = ([silent] if silent else []) + ["reset change: " + "; ".join(written.manifest["quantization"]["changes"])
             if written.manifest["quantization"].get("changes") else "no reset change: the model resets by subtraction"]
    return XyloCheckRecord(str(written.path), written.chip, written.manifest["quantization"]["rule"], inputs,
                           int(x.shape[0]), int(x.shape[1]), stages, losses, events, overall, ceiling, alive, notes)


def open_or_compile(graph: Graph, artefact: Path | None, lower_artefact) -> tuple[Any, tempfile.TemporaryDirectory | None]:
    """The written artefact at ``artefact``; None: ``lower_artefact()`` (what compile writes) written to a
    temporary directory and read back (the caller keeps the directory until done)."""
    from snncc.targets.xylo.artefact.read import read_artefact

    if artefact is not None:
        return read_artefact(artefact), None
    tmp = tempfile.TemporaryDirectory(prefix="snncc-xylo-check-")
    path = Path(tmp.name) / "model.xylo"
    lower_artefact().write(path)
    return read_artefact(path), tmp
