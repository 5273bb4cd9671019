"""Population activity of an IR graph in float on given inputs, and the warning for a silent model.

One record, ``SpikeActivity``, for a population's activity on B samples of T steps (in float or on a
target, from its spike counts; ``Tally`` gathers them chunk by chunk):

    rate              = spikes / (neurons * B * T)        mean spikes per neuron and step
    silent_neurons    = neurons that never spike on any sample
    saturated_neurons = neurons that spike at every step they can on every sample (ceil(T / r)
                        spikes, r the refractory period in steps)
    peak              = max over samples, steps and neurons of V / threshold (float runs with
                        voltages only: ``population_activity``; V as the reference simulator records
                        it, after any reset; for a population that never spikes, how close it came)

A population is *silent* when no neuron spikes, *saturated* when every neuron is saturated;
``flagged`` names either in one line with its figures (compile and check report them, float and on
the target).

A model is silent in float when the population its readout counts never spikes, or (without a
readout) no spiking population does. Compile then warns in one line naming the first silent
population, how close it came and the likely cause (``silence_warning``): a model silent in
float compiles to an artefact that is "exact" and says nothing.

The calibration inputs are the Loihi compiler's (its scale rule is measured on them):
``CALIBRATION_BATCH`` seeded random spike trains of density ``CALIBRATION_RATE``, seed
``CALIBRATION_SEED``. They are SYNTHETIC.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

CALIBRATION_BATCH = 8
CALIBRATION_RATE = 0.05
CALIBRATION_SEED = 1
FAR_BELOW = 0.5            # a silent population whose V peaks below this fraction of its threshold


def calibration_spikes(width: int, steps: int, *, batch: int = CALIBRATION_BATCH, rate: float = CALIBRATION_RATE,
                       seed: int = CALIBRATION_SEED) -> np.ndarray:
    """(batch, steps, width) uint8 seeded random spike trains: each entry 1 with probability ``rate``."""
    return (np.random.default_rng(seed).random((batch, steps, width)) < rate).astype(np.uint8)


def calibration_text(steps: int) -> str:
    return (f"{CALIBRATION_BATCH} seeded random spike trains (p={CALIBRATION_RATE}, seed {CALIBRATION_SEED}), "
            f"{steps} steps")


def spiking_populations(graph: Graph) -> list[str]:
    """The LIF populations that can spike (some finite threshold), in the graph's order."""
    from snncc.ir.nodes import LIF

    return [name for name in graph.of_kind(LIF) if np.any(np.isfinite(graph.node(name).threshold))]


def population_activity(graph: Graph, inputs: np.ndarray) -> dict[str, SpikeActivity]:
    """``SpikeActivity`` of every spiking population of ``graph`` on ``inputs``, in float64, with its ``peak``."""
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    names = spiking_populations(graph)
    if not names:
        return {}
    with one_thread():
        res = simulate(graph, inputs, record="voltage")
    refractory = graph_refractory(graph)
    out = {}
    for name in names:
        theta = np.asarray(graph.node(name).threshold, np.float64)
        finite = np.isfinite(theta) & (theta > 0)
        v = np.asarray(res.voltage[name])[..., finite] / theta[finite]
        out[name] = spike_activity(np.asarray(res.spikes[name]), refractory.get(name, 1))
        out[name].peak = float(v.max()) if v.size else 0.0
    return out


def _read_out(graph: Graph) -> list[str]:
    """The populations whose spikes a Readout counts."""
    from snncc.ir.nodes import Readout

    return [p for r in graph.of_kind(Readout) for p in graph.predecessors(r)]


def silent_population(graph: Graph, activity: Mapping[str, SpikeActivity]) -> str | None:
    """The first silent population if the model is silent in float (module docstring), else None."""
    if not activity:
        return None
    counted = [p for p in _read_out(graph) if p in activity] or list(activity)
    if not all(activity[p].silent for p in counted):
        return None
    return next(name for name, a in activity.items() if a.silent)


def silence_warning(graph: Graph, activity: Mapping[str, SpikeActivity], inputs: str, steps: int) -> str | None:
    """One line for a model silent in float on ``inputs`` (described; ``steps`` long), naming the likely
    cause; else None. dt is the likely cause when the silent population's longest time constant outlasts
    the sample (a step then moves V by a small fraction of its input); threshold or gain scale when V
    peaks below ``FAR_BELOW`` of the threshold; otherwise the inputs or thresholds are near the edge."""
    name = silent_population(graph, activity)
    if name is None:
        return None
    op, peak = graph.node(name), activity[name].peak or 0.0
    taus = np.concatenate([np.asarray(op.tau_syn, np.float64), np.asarray(op.tau_mem, np.float64)]) / graph.dt
    taus = taus[np.isfinite(taus) & (taus < 1e20)]          # IF/I populations carry a 1e30 s "no leak"
    head = (f"the model never spikes in float on {inputs}: population '{name}' stays silent (its voltage peaks at "
            f"{peak:.3g} x threshold)")
    if taus.size and float(np.max(taus)) > steps:
        cause = (f"likely cause: dt; at dt = {graph.dt:g} s its time constants are {float(np.min(taus)):.4g} to "
                 f"{float(np.max(taus)):.4g} steps, longer than the {steps}-step sample: pass the dt the model was "
                 "trained at (--dt)")
    elif peak < FAR_BELOW:
        cause = ("likely cause: threshold or gain scale; check the thresholds against the input weights and gains "
                 "(NIR r and w_in)")
    else:
        cause = "its voltage comes close: the inputs may be too sparse for it, or the thresholds a little high"
    return f"{head}; {cause}. The artefact reproduces a silent model, so its exactness says nothing about it"


def calibration_warning(graph: Graph, steps: int, known: Mapping[str, SpikeActivity] | None = None) -> str | None:
    """``silence_warning`` on the calibration inputs of ``steps`` steps; None for a graph that is not one
    spike Input feeding spiking populations (LSTMs, analog inputs). ``known``: the float activity on those
    inputs where a target already measured it (``targets.base.KnowsFloatActivity``): a model none of whose
    populations is silent there needs no run (no warning); otherwise the float model runs for the figures."""
    from snncc.ir.nodes import Input

    inputs = graph.of_kind(Input)
    populations = spiking_populations(graph)
    if len(inputs) != 1 or graph.node(inputs[0]).signal != "spikes" or not populations:
        return None
    if known is not None and all(p in known and not known[p].silent and known[p].steps == steps
                                 and known[p].samples == CALIBRATION_BATCH for p in populations):
        return None
    x = calibration_spikes(graph.node(inputs[0]).width, steps)
    return silence_warning(graph, population_activity(graph, x), calibration_text(steps), steps)


@dataclass
class SpikeActivity:
    """One population's activity on ``samples`` x ``steps`` (module docstring)."""

    neurons: int
    samples: int
    steps: int
    spikes: int
    rate: float                  # spikes per neuron and step
    silent_neurons: int
    saturated_neurons: int
    peak: float | None = None    # max V / threshold, where the float voltages were recorded

    @property
    def silent(self) -> bool:
        return self.spikes == 0

    @property
    def status(self) -> str:
        if self.spikes == 0:
            return "silent"
        if self.neurons and self.saturated_neurons == self.neurons:
            return "saturated"
        return "active"

    def as_dict(self) -> dict[str, Any]:
        figures = {k: v for k, v in asdict(self).items() if k != "peak" or v is not None}
        return {**figures, "status": self.status}

    def text(self) -> str:
        return (f"{self.spikes} spikes ({self.rate:.4f} per neuron and step), {self.silent_neurons}/{self.neurons} "
                f"neurons silent, {self.saturated_neurons}/{self.neurons} at every step they can")


def activity_from_counts(counts: np.ndarray, steps: int, refractory: int = 1) -> SpikeActivity:
    """Activity of one population from its per-sample spike counts (B, n) over ``steps`` steps."""
    counts = np.asarray(counts, np.int64)
    b, n = counts.shape
    t = int(steps)
    most = math.ceil(t / max(int(refractory), 1)) if t else 0
    saturated = int(np.sum(np.all(counts >= most, axis=0))) if b and t else 0
    total = int(counts.sum())
    return SpikeActivity(neurons=int(n), samples=int(b), steps=t, spikes=total,
                              rate=total / (b * t * n) if b * t * n else 0.0,
                              silent_neurons=int(np.sum(counts.sum(axis=0) == 0)), saturated_neurons=saturated)


def spike_activity(spikes: np.ndarray, refractory: int = 1) -> SpikeActivity:
    """Activity of one population from its spikes (B, T, n) 0/1."""
    s = np.asarray(spikes)
    if s.ndim == 2:
        s = s[None]
    return activity_from_counts(s.sum(axis=1, dtype=np.int64), s.shape[1], refractory)


def activity(spikes: Mapping[str, np.ndarray], refractory: Mapping[str, int] | None = None
             ) -> dict[str, SpikeActivity]:
    """``spike_activity`` of every population in ``spikes`` (name -> (B, T, n))."""
    refractory = refractory or {}
    return {name: spike_activity(s, int(refractory.get(name, 1))) for name, s in spikes.items()}


class Tally:
    """Per-sample spike counts of several populations, gathered chunk by chunk (``add``), read as
    activity (``activity``): long runs never hold every spike in memory."""

    def __init__(self) -> None:
        self.counts: dict[str, list[np.ndarray]] = {}
        self.steps = 0

    def add(self, spikes: Mapping[str, np.ndarray]) -> None:
        for name, s in spikes.items():
            self.counts.setdefault(name, []).append(np.asarray(s).sum(axis=1, dtype=np.int64))
            self.steps = int(np.shape(s)[1])

    def of(self, name: str) -> np.ndarray:
        """(B, n) counts of ``name`` over every chunk added."""
        return np.concatenate(self.counts[name])

    def activity(self, refractory: Mapping[str, int] | None = None) -> dict[str, SpikeActivity]:
        refractory = refractory or {}
        return {name: activity_from_counts(self.of(name), self.steps, int(refractory.get(name, 1)))
                for name in self.counts}


def graph_refractory(graph) -> dict[str, int]:
    """Each LIF population's refractory period in steps (the IR's ``refractory``, at least 1)."""
    from snncc.ir.nodes import LIF

    return {name: max(int(graph.node(name).refractory), 1) for name in graph.of_kind(LIF)}


def flagged(figures: Mapping[str, SpikeActivity], where: str) -> list[str]:
    """One line per silent or saturated population: ``where`` (e.g. "in float") and its figures."""
    lines = []
    for name, a in figures.items():
        if a.status == "silent":
            lines.append(f"population '{name}' never spikes {where} ({a.samples} samples x {a.steps} steps, "
                         f"{a.neurons} neurons)")
        elif a.status == "saturated":
            lines.append(f"population '{name}' spikes at every step it can {where} ({a.samples} samples x {a.steps} "
                         f"steps, {a.neurons} neurons, rate {a.rate:.3f})")
    return lines


def as_dicts(figures: Mapping[str, SpikeActivity]) -> dict[str, dict[str, Any]]:
    return {name: a.as_dict() for name, a in figures.items()}


def float_silence_warning(graph: Graph, inputs: np.ndarray, figures: Mapping[str, SpikeActivity],
                          described: str = "these inputs") -> str | None:
    """``silence_warning`` (its rule: the read-out populations silent) when ``figures`` (float, on ``inputs``)
    show a silent population; the float run it needs (voltages) is made only then."""
    if not any(a.silent for name, a in figures.items() if name in spiking_populations(graph)):
        return None
    x = np.asarray(inputs)
    return silence_warning(graph, population_activity(graph, x), described, int(x.shape[1]))
