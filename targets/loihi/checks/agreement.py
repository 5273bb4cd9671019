"""Agreement of the written Loihi bundle with the float model, without labels.

For a graph that comes without a data set (a NIR export, say), what deployment loses is measured
against the float model itself, on user-supplied spike trains or on seeded random ones of a stated
density (each channel spikes with probability ``density`` per step, independently), as long as
the bundle's own sample (tSample less the outputs' shift):

    argmax agreement    share of decided samples whose emulated output-count argmax equals the float
                        one, with its count and 95 % interval (``snncc.measure.agreement``: samples
                        whose float output ties at the top or is silent are left out and counted)
    count correlation   Pearson correlation of all output spike counts (samples x classes), emulated vs
                        float (undefined when either is constant)
    per layer           share of equal spike entries (undefined when both are silent), and the
                        correlation of per-neuron spike counts
    liveness            every population's activity in float and on the bundle (``snncc.ir.liveness``)

The reference is the float model as trained, with its own reset. Beside it, each stage between the
model and the bundle is compared with the same reference on the same decided samples, so the loss
is broken down by cause: the reset change (``--allow-reset-change``), the timing change (the
order Loihi runs), quantization (parameters in float), and integer arithmetic (the bundle as
written, bit-exact). The stages are re-derived from the model (``written.py``); when that does not
reproduce the bundle only the bundle is compared. The ceiling beside it: the float model against
itself with every Dense weight multiplied by (1 + noise * N(0, 1)), noise 0.01 by default -- how
sensitive the model's decisions are to perturbations of that size on these inputs.
SYNTHETIC inputs (random spikes) say nothing about accuracy on real data.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.nodes import Conv, Dense
from snncc.measure.agreement import (UNDECIDED_RULE, ArgmaxAgreement, chunk_size, count_correlation,
                                     default_samples, default_samples_note, random_inputs)

DEFAULT_DENSITY = 0.08
DEFAULT_NOISE = 0.01
CHUNK = 64
STAGE_LABELS = {
    "reset_changed_float": "(r) float, reset to zero instead",
    "loihi_order_float": "(b) float, in the order Loihi runs",
    "quantized_float": "(c) float, quantized parameters",
    "emulator": "(d) the bundle as written, emulated",
}
CAUSES = (("reset", "reset_changed_float"), ("timing", "loihi_order_float"), ("quantization", "quantized_float"),
          ("integer_arithmetic", "emulator"))


def perturbed(graph: Graph, noise: float, seed: int) -> Graph:
    """A copy of ``graph`` with every Dense and Conv weight (and bias) multiplied by 1 + noise * N(0, 1)
    (pooling kernels, which hold no trained weights, are left as they are)."""
    g = graph.copy()
    rng = np.random.default_rng(seed)
    for name, op in g.items():
        pooling = (isinstance(op, Conv) and op.weight.shape[1] == 1 and op.groups == op.in_shape[0]
                   and bool(np.all(op.weight == op.weight.flat[0])))
        if isinstance(op, (Dense, Conv)) and not pooling:
            op.weight = op.weight * (1.0 + noise * rng.standard_normal(op.weight.shape))
            if op.bias is not None:
                op.bias = op.bias * (1.0 + noise * rng.standard_normal(np.shape(op.bias)))
    return g


@dataclass
class AgreementRecord:
    """The written bundle vs the float model as trained on unlabelled inputs, stage by stage, with the
    float model's noise ceiling and every population's liveness."""

    target: str
    inputs: str
    samples: int
    steps: int
    reference: str
    scale_rule: str
    scale_reason: str
    argmax_agreement: float | None               # the bundle's share (None: undefined, e.g. outputs silent)
    argmax: dict[str, Any]                       # ArgmaxAgreement: decided, agreeing, ties, silent, low, high
    undecided_rule: str
    count_correlation: float | None
    layer_spike_agreement: dict[str, float | None]
    layer_count_correlation: dict[str, float | None]
    stages: dict[str, dict[str, Any]]            # stage -> ArgmaxAgreement against the model as trained
    causes: dict[str, float]                     # points of argmax agreement lost at each stage, and in total
    noise: float
    ceiling_argmax_agreement: float | None
    ceiling_count_correlation: float | None
    candidates: dict[str, float | None] = field(default_factory=dict)   # scale candidates' calibration errors
    overflow: dict[str, int] = field(default_factory=dict)
    liveness: dict[str, Any] = field(default_factory=dict)
    flagged: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def lines(self) -> list[str]:
        def corr(v):
            return "undefined (constant counts)" if v is None else f"{v:.4f}"

        ceiling = ("undefined" if self.ceiling_argmax_agreement is None else f"{self.ceiling_argmax_agreement:.3f}")
        out = [f"agreement of the Loihi bundle with {self.reference} on {self.inputs}",
               f"  scale rule '{self.scale_rule}': {self.scale_reason}",
               f"  argmax agreement   {ArgmaxAgreement(**self.argmax).text()}",
               f"                     (float model with {100 * self.noise:g} % weight noise: {ceiling})",
               f"  count correlation  {corr(self.count_correlation)}  (float model with {100 * self.noise:g} % weight "
               f"noise: {corr(self.ceiling_count_correlation)})",
               f"  rule: {self.undecided_rule}"]
        if len(self.stages) > 1:
            out.append("  stage by stage against the model as trained: " + "; ".join(
                f"{STAGE_LABELS.get(k, k)} " + ("undefined" if v["share"] is None else f"{v['share']:.3f}")
                for k, v in self.stages.items()))
        if self.causes:
            out.append("  agreement lost (points) from: " + ", ".join(f"{k} {v:+.1f}" for k, v in self.causes.items()))
        for name, a in self.layer_spike_agreement.items():
            out.append(f"  layer {name}: spike agreement "
                       + ("undefined (silent)" if a is None else f"{100 * a:.2f} %")
                       + f", count correlation {corr(self.layer_count_correlation[name])}")
        if self.candidates:
            out.append("  scale candidates (calibration spike-count error): " + ", ".join(
                f"{k} {'undefined' if v is None else f'{v:.4f}'}" for k, v in self.candidates.items()))
        if any(self.overflow.values()):
            out.append(f"  overflow events: {self.overflow}")
        out += [f"  liveness: {line}" for line in self.flagged]
        out += [f"  warning: {line}" for line in self.warnings]
        out += [f"  note: {n}" for n in self.notes]
        return out

    def render_text(self, console) -> None:
        for line in self.lines():
            console.print(line, markup=False, highlight=False, soft_wrap=True)


class _Pairs:
    """Running per-layer spike-entry agreement between two runs (both-silent chunks left out)."""

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


def measure_bundle(graph: Graph, bundle, inputs: np.ndarray | None = None, *, samples: int | None = None,
                   density: float = DEFAULT_DENSITY, seed: int = 0, noise: float = DEFAULT_NOISE, noise_seed: int = 9,
                   data: str | None = None, progress=None) -> AgreementRecord:
    """Emulate the written ``bundle`` (``written.WrittenBundle``) and compare it with ``graph``.

    ``inputs``: (N, T, C) 0/1 spikes; None draws ``samples`` seeded random spike trains of ``density``,
    the bundle's own length (default ``snncc.measure.agreement.default_samples``). ``progress(n)`` after
    each chunk of n samples."""
    from snncc.ir import liveness
    from snncc.ir.simulate import simulate
    from snncc.measure.agreement import argmax_agreement
    from snncc.targets.loihi.emulation.emulator import check_inputs
    from snncc.threads import one_thread

    if not noise >= 0:
        raise SnnccError(f"weight noise must be >= 0, got {noise}", field="--noise")
    net = bundle.network
    width = net.input_width
    if inputs is None:
        chosen = samples is None
        if chosen:
            samples = default_samples(sum(net.layers[bundle.layer_of[p]].model_n for p in bundle.populations),
                                      bundle.steps)
        x_all = random_inputs(samples, bundle.steps, width, density, seed)
        described = (f"{default_samples_note(samples) if chosen else f'{samples} samples'}: seeded random spike trains "
                     f"(density {density:g} per channel and step, seed {seed}), {bundle.steps} steps (SYNTHETIC)")
    else:
        x_all = check_inputs(inputs, width, source=data)
        described = f"{x_all.shape[0]} given spike trains of {x_all.shape[1]} steps"
    n, t, _ = x_all.shape
    names = bundle.populations
    last = names[-1]
    lowered = bundle.lowered
    stages: dict[str, Graph] = {}
    if lowered is not None:
        if lowered.deployed is not None:
            stages["reset_changed_float"] = lowered.deployed
        if lowered.order is not lowered.trained and lowered.order is not lowered.deployed:
            stages["loihi_order_float"] = lowered.order
        stages["quantized_float"] = lowered.quantized
    noisy_graph = perturbed(graph, noise, noise_seed)
    counts: dict[str, list[np.ndarray]] = {k: [] for k in ("trained", "noisy", "emulator", *stages)}
    float_tally, loihi_tally = liveness.Tally(), liveness.Tally()
    layers = _Pairs()
    overflow = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    chunk = chunk_size(sum(net.layers[bundle.layer_of[p]].model_n for p in names), t, CHUNK)
    for start in range(0, n, chunk):
        x = x_all[start:start + chunk]
        with one_thread():
            ref = simulate(graph, x, record="spikes")
            ref_spikes = {k: np.asarray(ref.spikes[k]).astype(np.uint8) for k in names}
            counts["trained"].append(ref_spikes[last].sum(axis=1, dtype=np.int64))
            for key, g in (("noisy", noisy_graph), *stages.items()):
                counts[key].append(np.asarray(simulate(g, x, record="spikes").spikes[last]).sum(axis=1).astype(np.int64))
        emu, res = bundle.run(x)
        counts["emulator"].append(emu[last].sum(axis=1, dtype=np.int64))
        for k, v in res.overflow.items():
            overflow[k] += v
        float_tally.add(ref_spikes)
        loihi_tally.add(emu)
        layers.add(emu, ref_spikes)
        if progress is not None:
            progress(x.shape[0])
    c = {k: np.concatenate(v) for k, v in counts.items()}
    main = argmax_agreement(c["trained"], c["emulator"])
    stage_agreement = {k: argmax_agreement(c["trained"], c[k]) for k in (*stages, "emulator")}
    causes: dict[str, float] = {}
    if main.defined and lowered is not None:
        previous = 1.0
        for cause, key in CAUSES:
            if key in stage_agreement:
                causes[cause] = 100 * (previous - stage_agreement[key].share)
                previous = stage_agreement[key].share
        causes["total"] = 100 * (1.0 - main.share)
    f_act = float_tally.activity(liveness.graph_refractory(graph))
    l_act = loihi_tally.activity({nm: int(net.layers[bundle.layer_of[nm]].ref_delay) for nm in names})
    warning = liveness.float_silence_warning(graph, x_all[:chunk], f_act, f"the first {min(chunk, n)} of these samples")
    ceiling = argmax_agreement(c["trained"], c["noisy"])
    meta = net.metadata
    quant = meta.get("quantization") or {}
    notes = []
    if inputs is None:
        notes.append("random spike trains: agreement with the float model, not accuracy on real data")
    if bundle.stages_note:
        notes.append(bundle.stages_note)
    if lowered is not None and lowered.deployed is not None:
        notes.append("the bundle resets to zero where the model subtracts (--allow-reset-change): the reference is the "
                     "model as trained; stage (r) is the changed float model, so the cost of the change is a cause above")
    if t != bundle.steps:
        notes.append(f"the inputs have {t} steps; the bundle's tSample is for {bundle.steps} (the emulator runs the "
                     "inputs' length)")
    return AgreementRecord(
        target="loihi", inputs=described, samples=n, steps=t,
        reference="the float model as trained (its own reset)",
        scale_rule=str(quant.get("rule", "unknown")), scale_reason=str(quant.get("reason", "not recorded")),
        argmax_agreement=main.share, argmax=main.as_dict(), undecided_rule=UNDECIDED_RULE,
        count_correlation=count_correlation(c["emulator"], c["trained"]),
        layer_spike_agreement=layers.shares(),
        layer_count_correlation={k: count_correlation(loihi_tally.of(k), float_tally.of(k)) for k in names},
        stages={k: v.as_dict() for k, v in stage_agreement.items()}, causes=causes,
        noise=float(noise), ceiling_argmax_agreement=ceiling.share,
        ceiling_count_correlation=count_correlation(c["noisy"], c["trained"]),
        candidates=dict((quant.get("calibration") or {}).get("errors", {})), overflow=overflow,
        liveness={"float": liveness.as_dicts(f_act), "loihi": liveness.as_dicts(l_act)},
        flagged=liveness.flagged(f_act, "in float") + liveness.flagged(l_act, "on Loihi (the bundle)"),
        warnings=[warning] if warning else [], notes=notes)


def measure_agreement(graph: Graph, options: dict[str, Any], inputs: np.ndarray | None = None, **kw) -> AgreementRecord:
    """``measure_bundle`` on the bundle ``compile`` would write for ``graph`` with ``options`` (written to a
    temporary directory and read back: the measured network is the file's)."""
    from snncc.targets.kit.measured import compiled as compiled_artefact
    from snncc.targets import get_target
    from snncc.targets.loihi.checks.written import open_bundle

    with compiled_artefact(get_target("loihi"), graph, options) as path:
        return measure_bundle(graph, open_bundle(path, graph), inputs, data=options.get("data"), **kw)
