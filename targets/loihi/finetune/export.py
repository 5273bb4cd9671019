"""A fine-tuned network read back as a float graph, and checked as compile checks a lowering.

    adapted_graph(lowered, network)     the IR in the order Loihi runs with ``network``'s registers in float units
                                        (what ``--finetune-out`` writes as NIR)
    validate_export(lowered, network)   ``checks/exactness.validate_lowering`` of the fine-tuned network against it
"""

from __future__ import annotations

import numpy as np

from snncc.ir.graph import Graph


def adapted_graph(lowered, network) -> Graph:
    """``lowered.order`` (the IR in the order and reset Loihi runs) with ``network``'s registers read
    back in float units, as ``quantize.quantize_graph`` reads back the quantized registers:
    W = w_q * 2**e / s, theta = vThMant / s, decays from the registers (exp discretisation), current
    biases from their always-on source columns, voltage biases b * 2**biasExp / (64 s)."""
    from snncc.targets.kit.graphs import BiasTerm, current_biases, restore_biases
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
