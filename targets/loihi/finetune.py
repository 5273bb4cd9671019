"""Deployment fine-tuning for Loihi 1: the lowered network's integer arithmetic as the student.

    lower      ``lower_model(graph, options)`` as ``compile`` does (scale rule, timing, reset change)
    student    ``DifferentiableLoihi`` over the lowered network (``lowering/differentiable.py``): equal
               to the emulator on the registers it exports; the rule's format is kept
    teacher    the graph as trained (its own reset: a subtract-reset graph stays subtract)
    export     a LoihiNetwork with the fine-tuned registers, checked by the compiler's own validation
               (``checks/exactness.validate_lowering``: timing, registers and kernel against the IR)
               against the fine-tuned parameters read back as a float graph (``adapted_graph``)

``finetune_artefact`` is the target's ``finetune`` capability (``snncc compile --finetune``): the
fine-tuned network placed on cores and written as any bundle (``lowering/lower.attach_core_map``,
``bundle/hdf5.py``), its record under /snncc/finetune and in /snncc/metadata.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph


@dataclass
class LoihiFinetuned:
    """The result: the network to write, the lowering it came from, the record, the adapted float graph."""

    network: Any                 # LoihiNetwork with the fine-tuned registers
    lowered: Any                 # LoweredModel (before fine-tuning)
    record: Any                  # snncc.finetune.engine.FinetuneRecord
    adapted: Graph               # the fine-tuned parameters read back in float units (the deployed order)
    validation: dict = field(default_factory=dict)   # validate_lowering of the exported network

    def metadata(self) -> dict:
        """What the bundle records about its fine-tuning (JSON-ready)."""
        r = self.record
        return {"finetuned": True, "inputs": r.inputs, "seed": r.inputs["seed"], "steps": r.steps,
                "kept_epoch": r.kept_epoch, "agreement_before": r.held_out_before,
                "agreement_after": r.held_out_after, "teacher": "the float graph as trained (its own reset)"}


def loihi_student(lowered, steps: int, **kwargs):
    """The differentiable arithmetic of a LoweredModel (kwargs: learn, slope, detach_reset, device)."""
    from snncc.targets.loihi.lowering.differentiable import DifferentiableLoihi

    names = [c.lif for c in lowered.layers]
    return DifferentiableLoihi(lowered.network, names, lowered.timing_record.shifts, steps, **kwargs)


def network_counts(lowered, steps: int, network, x: np.ndarray) -> np.ndarray:
    """Output spike counts (B, classes) of ``network`` (``lowered``'s layout, any registers) on ``x``, run by the
    bit-exact emulator, over the model's own ``steps`` (population shifts undone)."""
    from snncc.targets.loihi.checks.exactness import lead_steps, loihi_spikes, pad
    from snncc.targets.loihi.emulation.emulator import emulate

    trec = lowered.timing_record
    res = emulate(network, pad(x, lead_steps(trec.shifts, trec.output_shift)), record="all")
    spikes = loihi_spikes(res, network, lowered.layers, trec.shifts, steps)
    return spikes[lowered.layers[-1].lif].sum(axis=1, dtype=np.int64)


def deployed_counts(lowered, steps: int) -> Callable[[Any, np.ndarray], np.ndarray]:
    """``(student, x) -> counts``: the student's exported network through ``network_counts``."""
    return lambda student, x: network_counts(lowered, steps, student.export(), x)


CALIBRATION_SAMPLES = 512   # training inputs whose teacher spikes give the compensated rounding its statistics
EXPONENT_SHIFTS = (1, 2)     # finer weight exponents tried for a projection with outliers (they clip)
SHIFT_RULES = ("per-layer", "split")   # rules whose projections each choose their exponent


def requantized(lowered, network, layer: int, which: str, exponent: int):
    """``network`` with projection ``which`` ("ff" or "rec") of layer ``layer`` (1..L) quantized again from the
    float weights at weight exponent ``exponent`` (weights beyond the 8-bit range clip: the format of a
    per-layer projection, one exponent, is kept). A new network; None when the projection has per-synapse
    exponents or the exponent is outside the chip's range."""
    import copy

    from snncc.passes.current_bias import current_biases
    from snncc.targets.loihi import chip
    from snncc.targets.loihi.lowering.quantize import quantize_weights

    if not chip.WGT_EXP_MIN <= exponent <= chip.WGT_EXP_MAX:
        return None
    c = lowered.layers[layer - 1]
    dense = c.ff if which == "ff" else c.rec
    scale = {p.dense: p.scale for p in lowered.quant_record.projections}[dense]
    net = copy.deepcopy(network)
    lay = net.layers[layer]
    m = lay.model_n
    w = lowered.order.node(dense).weight
    if which == "ff":
        if np.ndim(lay.wgt_exp):
            return None
        full = np.asarray(lay.weight).copy()
        full[:m, :w.shape[1]] = quantize_weights(w, scale, exponent)
        terms = current_biases(lowered.order, c.lif)
        if terms:
            repeats = (full.shape[1] - w.shape[1]) // len(terms)
            for j, t in enumerate(terms):
                q = quantize_weights(t.vector, scale, exponent)
                for r in range(repeats):
                    full[:m, w.shape[1] + j * repeats + r] = q
        lay.weight, lay.wgt_exp = full.astype(np.asarray(lay.weight).dtype), int(exponent)
    else:
        if lay.weight_rec is None or np.ndim(lay.wgt_exp_rec):
            return None
        full = np.asarray(lay.weight_rec).copy()
        full[:m, :m] = quantize_weights(w, scale, exponent)
        lay.weight_rec, lay.wgt_exp_rec = full.astype(np.asarray(lay.weight_rec).dtype), int(exponent)
    return net


def starting_points(lowered, make_student):
    """The search ``engine.finetune`` runs before training (``make_student(network)`` builds a student),
    greedy and measured on the validation part, keeping a change only when it is strictly better:

    1. per layer, the decay order (``DifferentiableLoihi.swap_decays``: exact below threshold, it moves
       what a reset to zero discards);
    2. per projection with outliers (max|W| > 20x the median |W|) under the per-layer or split rule, a
       weight exponent 1 or 2 finer than the rule's (the outliers clip, the bulk gains 1-2 bits);
    3. every layer's weights rounded with error feedback under the teacher's spikes on the first
       ``CALIBRATION_SAMPLES`` training inputs, at the rule's scales, then at per-neuron scales (at most 8
       per layer: ``rescale.py``; the exponents are kept).
    """
    import copy

    from snncc.targets.loihi.lowering.quantize import OUTLIER_RATIO

    def search(student, score, train):
        best, best_s = student, score(student)
        trace = [{"name": "as lowered", "validation": best_s}]
        for k, name in enumerate(best.populations):
            cand = copy.deepcopy(best)
            cand.swap_decays(k)
            s = score(cand)
            trace.append({"name": f"{name}: iDecay <-> vDecay", "validation": s})
            if s > best_s:
                best, best_s = cand, s
        if lowered.quant_record.rule in SHIFT_RULES:
            exps = {p.dense: p.wgt_exp for p in lowered.quant_record.projections}
            for i, c in enumerate(lowered.layers, start=1):
                for which, dense in (("ff", c.ff), ("rec", c.rec)):
                    if dense is None:
                        continue
                    w = np.abs(lowered.order.node(dense).weight)
                    nz = w[w > 0]
                    if not nz.size or w.max() <= OUTLIER_RATIO * np.median(nz):
                        continue
                    for shift in EXPONENT_SHIFTS:
                        net = requantized(lowered, best.export(), i, which, exps[dense] - shift)
                        if net is None:
                            continue
                        cand = make_student(net)
                        s = score(cand)
                        trace.append({"name": f"{dense}: wgtExp {exps[dense] - shift} (outliers clip)", "validation": s})
                        if s > best_s:
                            best, best_s = cand, s
        from snncc.targets.loihi.rescale import rescaled

        x, teacher_spikes, train_idx = train
        idx = train_idx[:CALIBRATION_SAMPLES]
        inputs, spikes = x[idx], {p: v[idx] for p, v in teacher_spikes.items()}
        moments: dict = {}      # the second moments, shared by both candidates
        for per_neuron, label in ((False, "compensated rounding at the rule's scales"),
                                  (True, "per-neuron scales (at most 8 per layer), compensated rounding")):
            net = rescaled(lowered, best.export(), inputs, spikes, per_neuron=per_neuron, moments=moments)
            if net is None:
                continue
            cand = make_student(net)
            s = score(cand)
            trace.append({"name": label, "validation": s})
            if s > best_s:
                best, best_s = cand, s
        return best, trace

    return search


def adapted_graph(lowered, network) -> Graph:
    """``lowered.order`` (the IR in the order and reset Loihi runs) with ``network``'s registers read
    back in float units, as ``quantize.quantize_graph`` reads back the quantized registers:
    W = w_q * 2**e / s, theta = vThMant / s, decays from the registers (exp discretisation), current
    biases from their always-on source columns, voltage biases b * 2**biasExp / (64 s)."""
    from snncc.passes.current_bias import BiasTerm, current_biases, restore_biases
    from snncc.targets.loihi import chip
    from snncc.targets.loihi.lowering.quantize import _tau_for, per_neuron

    g = lowered.order.copy()
    scales = {lq.lif: float(lq.scale) for lq in lowered.quant_record.layers}
    for c, lay in zip(lowered.layers, network.layers[1:]):
        s = scales[c.lif]
        op = g.node(c.lif)
        m = lay.model_n
        n_in = g.node(c.ff).weight.shape[1]
        exp = np.broadcast_to(np.asarray(lay.wgt_exp, np.int64), lay.weight.shape)
        w = np.asarray(lay.weight, np.float64) * 2.0 ** exp / s
        g.node(c.ff).weight = w[:m, :n_in].copy()
        terms = current_biases(lowered.order, c.lif)
        if terms:
            repeats = (lay.weight.shape[1] - n_in) // len(terms)
            restore_biases(g, c.lif, [BiasTerm(t.start, w[:m, n_in + j * repeats].copy(), t.origins)
                                      for j, t in enumerate(terms)])
        if c.rec:
            er = np.broadcast_to(np.asarray(lay.wgt_exp_rec, np.int64), lay.weight_rec.shape)
            g.node(c.rec).weight = (np.asarray(lay.weight_rec, np.float64) * 2.0 ** er / s)[:m, :m].copy()
        vth = np.broadcast_to(np.asarray(lay.v_th_mant, np.float64), (lay.n,))[:m]
        op.threshold = vth / s
        op.discretisation = "exp"
        op.tau_syn = per_neuron(np.broadcast_to(np.asarray(lay.i_decay), (lay.n,))[:m],
                                lambda r: _tau_for(g.dt, int(r)))
        op.tau_mem = per_neuron(np.broadcast_to(np.asarray(lay.v_decay), (lay.n,))[:m],
                                lambda r: _tau_for(g.dt, int(r)))
        if op.bias is not None and op.bias_placement == "voltage":
            op.bias = np.asarray(lay.bias, np.float64)[:m] * 2.0 ** lay.bias_exp / (2.0 ** chip.V_TH_SHIFT * s)
    return g


def validate_export(lowered, network, steps: int) -> dict:
    """The compiler's checks (``validate_lowering``) of a fine-tuned network: its timing against the IR,
    its registers against ``adapted_graph`` (in chip units), the fast kernel against the chip's rules."""
    from snncc.targets.loihi.checks.exactness import validate_lowering
    from snncc.targets.loihi.lowering.chip_units import in_chip_units

    adapted = in_chip_units(adapted_graph(lowered, network), lowered.quant_record)
    trec = lowered.timing_record
    return validate_lowering(lowered.trained, lowered.order, adapted, network, lowered.layers, trec.shifts,
                             trec.output_shift, steps=steps).as_dict()


def finetune_loihi(graph: Graph, options: dict[str, Any], split, *, config=None, task_sets=(), progress=None,
                   learn=("weights", "thresholds", "decays", "biases"), slope: float = 5.0,
                   search: bool = True) -> LoihiFinetuned:
    """Lower ``graph`` with ``options`` (as ``compile``), fine-tune the lowered network towards the
    graph as trained on ``split`` (``snncc.finetune.inputs``), check the result as compile checks a
    lowering. ``config``: ``snncc.finetune.engine.FinetuneConfig``; ``search``: measure the starting
    points of ``starting_points`` first."""
    from snncc.finetune.engine import FinetuneConfig, finetune
    from snncc.targets.loihi.lowering.lower import lower_model
    from snncc.training.device import resolve_device

    config = config or FinetuneConfig()
    steps = int(split.x.shape[1])
    lowered = lower_model(graph, dict(options, t_sample=steps))
    device = resolve_device(config.device)

    def make_student(network):
        from snncc.targets.loihi.lowering.differentiable import DifferentiableLoihi

        return DifferentiableLoihi(network, [c.lif for c in lowered.layers], lowered.timing_record.shifts, steps,
                                   learn=learn, slope=slope, device=device)

    student, record = finetune(make_student(lowered.network), lowered.trained, split, config=config,
                               deployed_counts=deployed_counts(lowered, steps),
                               starting_points=starting_points(lowered, make_student) if search else None,
                               task_sets=list(task_sets), progress=progress)
    network = student.export()
    result = LoihiFinetuned(network=network, lowered=lowered, record=record, adapted=adapted_graph(lowered, network))
    result.validation = validate_export(lowered, network, steps)
    network.metadata["finetune"] = result.metadata()
    if lowered.deployed is not None:
        record.notes.append("the teacher is the graph as trained (its own reset); Loihi runs it with reset to "
                            "zero (--allow-reset-change): the agreement includes the reset change")
    return result


# -- the capability: compile --finetune ------------------------------------------------------------------
@dataclass
class LoihiFinetunedArtefact:
    """``finetune``'s artefact: the Loihi bundle with the fine-tuned registers (written and summarised as
    ``lower``'s, plus a ``finetune`` entry) and the adapted float graph for ``--finetune-out``."""

    bundle: Any                  # LoihiArtefact of the fine-tuned network
    result: LoihiFinetuned

    def write(self, path) -> None:
        from snncc.targets.loihi.bundle.hdf5 import write_bundle

        b = self.bundle
        write_bundle(b.network, path, extra={"quantization": b.quantization, "timing": b.timing,
                                             "validation": b.validation, "finetune": self.finetune_record()})

    def summary(self) -> dict:
        return {**self.bundle.summary(), "finetune": self.finetune_record()}

    def render_text(self, console) -> None:
        self.bundle.render_text(console)
        for line in self.result.record.lines():
            console.print(line, markup=False)

    def adapted_graph(self) -> Graph:
        return self.result.adapted

    def finetune_record(self) -> dict:
        return {**self.result.metadata(), "record": self.result.record.as_dict()}


def finetune_artefact(graph: Graph, inputs, options: dict[str, Any], finetuning, *, labels=None,
                      data: str | None = None, progress=None) -> LoihiFinetunedArtefact:
    """``target.finetune``: fine-tune (``finetune_loihi``, the engine's default loss and schedule) on the
    user's data or seeded random spikes, place the result on cores and check it as ``lower`` checks a
    lowering (timing, registers and kernel against the adapted float graph)."""
    from snncc.errors import InternalError
    from snncc.finetune.engine import FinetuneConfig
    from snncc.finetune.inputs import model_split
    from snncc.targets.loihi.lowering.artefact import LoihiArtefact
    from snncc.targets.loihi.lowering.lower import attach_core_map
    from snncc.targets.loihi.mapping.relays import needs_relays
    from snncc.training.device import resolve_device

    device = finetuning.device or "cpu"
    resolve_device(device)                      # an unavailable device is refused before any work
    split = model_split(graph, inputs, labels, time_steps=options.get("time_steps"), density=finetuning.density,
                        samples=finetuning.finetune_samples, seed=finetuning.finetune_seed, data=data)
    config = FinetuneConfig(epochs=finetuning.finetune_epochs, seed=finetuning.finetune_seed, device=device)
    result = finetune_loihi(graph, options, split, config=config, progress=progress)
    network = result.network
    if needs_relays(network):
        raise SnnccError("fine-tuning a network whose fan-in needs relay neurons is not supported", field="--finetune")
    attach_core_map(network)
    checks = result.validation
    if not all(checks.get(k) for k in ("timing_exact", "quantized_params_exact", "kernel_exact")):
        raise InternalError("the fine-tuned bundle differs from its adapted float graph in the emulator "
                            f"({ {k: checks.get(k) for k in ('timing_exact', 'quantized_params_exact', 'kernel_exact')} })")
    lowered = result.lowered
    notes = list(lowered.notes) + [f"tSample {network.t_sample}: {network.metadata['t_sample_rule']}"]
    notes.append("fine-tuned: registers trained through Loihi's integer arithmetic towards the float graph as "
                 "trained; the checks above compare the bundle with the adapted float graph (--finetune-out)")
    bundle = LoihiArtefact(network=network, quantization=lowered.quant_record.as_dict(),
                           timing=lowered.timing_record.as_dict(), validation=checks, notes=notes)
    return LoihiFinetunedArtefact(bundle, result)
