"""Population activity of an IR graph in float on given inputs, and the warning for a silent model.

For every spiking LIF population (a finite threshold somewhere) on inputs (B, T, C):

    rate           = spikes / (neurons * B * T)        mean spikes per neuron and step
    silent_neurons = neurons that never spike on any input
    peak           = max over samples, steps and neurons of V / threshold (V as the reference
                     simulator records it, after any reset; for a population that never spikes
                     this is how close it came)

A model is silent in float when the population its readout counts never spikes, or (without a
readout) no spiking population does. Compile then warns in one line naming the first silent
population, how close it came and the likely cause (``silence_warning``): a model silent in
float compiles to an artefact that is "exact" and says nothing.

The calibration inputs are the Loihi compiler's (its scale rule is measured on them):
``CALIBRATION_BATCH`` seeded random spike trains of density ``CALIBRATION_RATE``, seed
``CALIBRATION_SEED``. They are SYNTHETIC.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

CALIBRATION_BATCH = 8
CALIBRATION_RATE = 0.05
CALIBRATION_SEED = 1
FAR_BELOW = 0.5            # a silent population whose V peaks below this fraction of its threshold


@dataclass
class PopulationActivity:
    """One spiking population's activity on the inputs it was measured on."""

    name: str
    neurons: int
    rate: float
    silent_neurons: int
    peak: float            # max V / threshold

    @property
    def silent(self) -> bool:
        return self.rate == 0.0

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


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


def population_activity(graph: Graph, inputs: np.ndarray) -> dict[str, PopulationActivity]:
    """``PopulationActivity`` of every spiking population of ``graph`` on ``inputs``, in float64."""
    from snncc.ir.simulate import simulate
    from snncc.threads import one_thread

    names = spiking_populations(graph)
    if not names:
        return {}
    with one_thread():
        res = simulate(graph, inputs, record="all")
    out = {}
    for name in names:
        spikes = res.spikes[name].numpy()
        theta = np.asarray(graph.node(name).threshold, np.float64)
        finite = np.isfinite(theta) & (theta > 0)
        v = res.voltage[name].numpy()[..., finite] / theta[finite]
        out[name] = PopulationActivity(
            name=name, neurons=int(spikes.shape[-1]), rate=float(spikes.mean()) if spikes.size else 0.0,
            silent_neurons=int(np.sum(~spikes.any(axis=(0, 1)))), peak=float(v.max()) if v.size else 0.0)
    return out


def _read_out(graph: Graph) -> list[str]:
    """The populations whose spikes a Readout counts."""
    from snncc.ir.nodes import Readout

    return [p for r in graph.of_kind(Readout) for p in graph.predecessors(r)]


def silent_population(graph: Graph, activity: dict[str, PopulationActivity]) -> str | None:
    """The first silent population if the model is silent in float (module docstring), else None."""
    if not activity:
        return None
    counted = [p for p in _read_out(graph) if p in activity] or list(activity)
    if not all(activity[p].silent for p in counted):
        return None
    return next(name for name, a in activity.items() if a.silent)


def silence_warning(graph: Graph, activity: dict[str, PopulationActivity], inputs: str, steps: int) -> str | None:
    """One line for a model silent in float on ``inputs`` (described; ``steps`` long), naming the likely
    cause; else None. dt is the likely cause when the silent population's longest time constant outlasts
    the sample (a step then moves V by a small fraction of its input); threshold or gain scale when V
    peaks below ``FAR_BELOW`` of the threshold; otherwise the inputs or thresholds are near the edge."""
    name = silent_population(graph, activity)
    if name is None:
        return None
    op, peak = graph.node(name), activity[name].peak
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


def calibration_warning(graph: Graph, steps: int) -> str | None:
    """``silence_warning`` on the calibration inputs of ``steps`` steps; None for a graph that is not one
    spike Input feeding spiking populations (LSTMs, analog inputs)."""
    from snncc.ir.nodes import Input

    inputs = graph.of_kind(Input)
    if len(inputs) != 1 or graph.node(inputs[0]).signal != "spikes" or not spiking_populations(graph):
        return None
    x = calibration_spikes(graph.node(inputs[0]).width, steps)
    return silence_warning(graph, population_activity(graph, x), calibration_text(steps), steps)
