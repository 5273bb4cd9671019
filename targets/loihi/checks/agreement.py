"""Agreement of the emulated Loihi bundle with the float graph, without labels.

For a graph that comes without a data set (a NIR export, say), what deployment loses is measured
against the float model itself, on user-supplied spike trains or on seeded random ones of a stated
density (each channel spikes with probability ``density`` per step, independently):

    argmax agreement    share of samples whose emulated output-count argmax equals the float one
    count correlation   Pearson correlation of all output spike counts (samples x classes), emulated vs float
    per layer           share of equal spike entries, and the correlation of per-neuron spike counts

The float reference is the graph as deployed in float: the graph as given, with only the reset
changed when ``allow_reset_change`` replaced a subtract reset (the cost of the reset itself is
measured by ``snncc check --data``). The ceiling beside it: the float graph against itself with
every Dense weight multiplied by (1 + noise * N(0, 1)), noise 0.01 by default -- how sensitive the
graph's decisions are to perturbations of that size on these inputs (8-bit weights are finer than
1 % multiplicative noise, so a deployment should come close to this figure).
SYNTHETIC inputs (random spikes) say nothing about accuracy on real data.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import Dense

DEFAULT_SAMPLES = 40
DEFAULT_STEPS = 256
DEFAULT_DENSITY = 0.08
DEFAULT_NOISE = 0.01


def random_inputs(samples: int, steps: int, width: int, density: float, seed: int) -> np.ndarray:
    """(samples, steps, width) 0/1 spikes, each entry 1 with probability ``density`` (seeded)."""
    if not 0.0 < density <= 1.0:
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    if samples < 1 or steps < 1:
        raise SnnccError("need at least one sample and one step", field="--limit")
    return (np.random.default_rng(seed).random((samples, steps, width)) < density).astype(np.uint8)


def count_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation of two count arrays (flattened); 1.0 when both are equal and constant."""
    a, b = np.asarray(a, np.float64).reshape(-1), np.asarray(b, np.float64).reshape(-1)
    if a.std() == 0 or b.std() == 0:
        return 1.0 if np.array_equal(a, b) else 0.0
    return float(np.corrcoef(a, b)[0, 1])


def perturbed(graph: Graph, noise: float, seed: int) -> Graph:
    """A copy of ``graph`` with every Dense weight (and Dense bias) multiplied by 1 + noise * N(0, 1)."""
    g = graph.copy()
    rng = np.random.default_rng(seed)
    for name, op in g.items():
        if isinstance(op, Dense):
            op.weight = op.weight * (1.0 + noise * rng.standard_normal(op.weight.shape))
            if op.bias is not None:
                op.bias = op.bias * (1.0 + noise * rng.standard_normal(np.shape(op.bias)))
    return g


@dataclass
class AgreementRecord:
    """Emulated bundle vs float graph on unlabelled inputs, with the float graph's noise ceiling."""

    inputs: str
    samples: int
    steps: int
    reference: str
    scale_rule: str
    scale_reason: str
    argmax_agreement: float
    count_correlation: float
    layer_spike_agreement: dict[str, float]
    layer_count_correlation: dict[str, float]
    noise: float
    ceiling_argmax_agreement: float
    ceiling_count_correlation: float
    candidates: dict[str, float] = field(default_factory=dict)   # scale candidates' calibration errors
    overflow: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def lines(self) -> list[str]:
        out = [f"agreement of the Loihi emulator with {self.reference} on {self.inputs}",
               f"  scale rule '{self.scale_rule}': {self.scale_reason}",
               f"  argmax agreement   {self.argmax_agreement:.3f}   (float graph with {100 * self.noise:g} % weight "
               f"noise: {self.ceiling_argmax_agreement:.3f})",
               f"  count correlation  {self.count_correlation:.4f}  (float graph with {100 * self.noise:g} % weight "
               f"noise: {self.ceiling_count_correlation:.4f})"]
        for name, a in self.layer_spike_agreement.items():
            out.append(f"  layer {name}: spike agreement {100 * a:.2f} %, count correlation "
                       f"{self.layer_count_correlation[name]:.4f}")
        if self.candidates:
            out.append("  scale candidates (calibration spike-count error): "
                       + ", ".join(f"{k} {v:.4f}" for k, v in self.candidates.items()))
        if any(self.overflow.values()):
            out.append(f"  overflow events: {self.overflow}")
        out += [f"  note: {n}" for n in self.notes]
        return out

    def render_text(self, console) -> None:
        for line in self.lines():
            console.print(line, markup=False, highlight=False, soft_wrap=True)


def measure_agreement(graph: Graph, options: dict[str, Any], inputs: np.ndarray | None = None, *,
                      samples: int = DEFAULT_SAMPLES, steps: int = DEFAULT_STEPS, density: float = DEFAULT_DENSITY,
                      seed: int = 0, noise: float = DEFAULT_NOISE, noise_seed: int = 9) -> AgreementRecord:
    """Lower ``graph`` for Loihi with ``options`` (as ``compile``), emulate it and compare with the float graph.

    ``inputs``: (N, T, C) 0/1 spikes; None draws ``samples`` x ``steps`` seeded random spikes of ``density``.
    """
    from snncc.targets.loihi import lower_model
    from snncc.targets.loihi.emulation.emulator import check_inputs, emulate
    from snncc.targets.loihi.checks.exactness import ir_spikes, lead_steps, loihi_spikes, pad
    from snncc.threads import one_thread
    from snncc.ir.simulate import simulate

    if not noise >= 0:
        raise SnnccError(f"weight noise must be >= 0, got {noise}", field="--noise")
    from snncc.targets.loihi.lowering.registers import chain

    width = graph.node(chain(graph)[0].pre).width
    if inputs is None:
        x = random_inputs(samples, steps, width, density, seed)
        described = (f"{samples} seeded random spike trains (density {density:g} per channel and step, seed {seed}), "
                     f"{steps} steps (SYNTHETIC)")
    else:
        x = check_inputs(inputs, width, source=options.get("data"))
        described = f"{x.shape[0]} given spike trains of {x.shape[1]} steps"
    n, t, _ = x.shape
    lowered = lower_model(graph, dict(options, t_sample=options.get("t_sample") or t))
    reference = lowered.deployed if lowered.deployed is not None else lowered.trained
    ref_name = ("the float graph with reset to zero (the deployed reset)" if lowered.deployed is not None
                else "the float graph")
    names = [c.lif for c in lowered.layers]
    net, trec = lowered.network, lowered.timing_record
    res = emulate(net, pad(x, lead_steps(trec.shifts, trec.output_shift)), record="all")
    emu = loihi_spikes(res, net, lowered.layers, trec.shifts, t)
    ref = ir_spikes(reference, x, names)
    last = names[-1]
    c_emu, c_ref = emu[last].sum(axis=1, dtype=np.int64), ref[last].sum(axis=1, dtype=np.int64)
    with one_thread():
        noisy = simulate(perturbed(reference, noise, noise_seed), x, record="spikes")
    c_noisy = noisy.spikes[last].numpy().sum(axis=1)
    q = lowered.quant_record
    calib = q.calibration or {}
    notes = []
    if inputs is None:
        notes.append("random spike trains: agreement with the float graph, not accuracy on real data")
    return AgreementRecord(
        inputs=described, samples=n, steps=t, reference=ref_name, scale_rule=q.rule, scale_reason=q.reason,
        argmax_agreement=float(np.mean(np.argmax(c_emu, axis=1) == np.argmax(c_ref, axis=1))),
        count_correlation=count_correlation(c_emu, c_ref),
        layer_spike_agreement={k: float(np.mean(emu[k] == ref[k])) for k in names},
        layer_count_correlation={k: count_correlation(emu[k].sum(axis=1), ref[k].sum(axis=1)) for k in names},
        noise=float(noise),
        ceiling_argmax_agreement=float(np.mean(np.argmax(c_noisy, axis=1) == np.argmax(c_ref, axis=1))),
        ceiling_count_correlation=count_correlation(c_noisy, c_ref),
        candidates=dict(calib.get("errors", {})), overflow=dict(res.overflow), notes=notes)
