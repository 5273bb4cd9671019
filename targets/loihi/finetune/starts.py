"""Fine-tuning's starting points for Loihi: the search ``engine.finetune`` runs before training.

Greedy and measured on the validation part, a change kept only when it is strictly better: the decay
order per layer, a finer weight exponent for a projection with outliers, and the weights rounded with
error feedback at the rule's and at per-neuron scales (``rescale.py``).
"""

from __future__ import annotations

import numpy as np

CALIBRATION_SAMPLES = 512   # training inputs whose teacher spikes give the compensated rounding its statistics
EXPONENT_SHIFTS = (1, 2)     # finer weight exponents tried for a projection with outliers (they clip)
SHIFT_RULES = ("per-layer", "split")   # rules whose projections each choose their exponent


def requantized(lowered, network, layer: int, which: str, exponent: int):
    """``network`` with projection ``which`` ("ff" or "rec") of layer ``layer`` (1..L) quantized again from the
    float weights at weight exponent ``exponent`` (weights beyond the 8-bit range clip: the format of a
    per-layer projection, one exponent, is kept). A new network; None when the projection has per-synapse
    exponents or the exponent is outside the chip's range."""
    import copy

    from snncc.targets.kit.graphs import current_biases
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
        from snncc.targets.loihi.finetune.rescale import rescaled

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
