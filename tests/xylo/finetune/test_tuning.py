"""Fine-tuning a XyloSpec towards a float teacher through the common engine (targets/xylo/finetune.py)."""

from __future__ import annotations

import json

import numpy as np

from snncc.finetune.engine import FinetuneConfig
from snncc.finetune.inputs import split_inputs
from snncc.targets.xylo.emulation.emulator import emulate
from snncc.targets.xylo.finetune.tuning import finetune_xylo
from snncc.targets.xylo.spec import XyloSpec
from tests.finetune.test_engine import STEPS, kept_by_the_rule, tiny_graph


def hand_mapped(graph, scale: float = 400.0) -> XyloSpec:
    """A plain mapping of the tiny graph (hidden LIFs -> hidden neurons, output LIFs -> Xylo's output neurons):
    weights x scale in int8 with one shift per matrix, thresholds x scale, decays 2**-d ~ dt / tau."""
    def int8(w):
        shift = max(0, int(np.ceil(np.log2(max(np.abs(w).max() * scale, 1) / 127))))
        return np.clip(np.rint(w * scale / 2 ** shift), -128, 127).astype(np.int8), shift

    w_in, s_in = int8(graph.node("w_in").weight.T)
    w_rec, s_rec = int8(graph.node("w_rec").weight.T)
    w_out, s_out = int8(graph.node("w_out").weight.T)
    h, o = graph.node("hidden"), graph.node("out")

    def dash(tau, n):
        return np.full(n, int(np.clip(np.rint(np.log2(np.mean(tau) / graph.dt)), 0, 15)), np.uint8)

    return XyloSpec(weights_in=w_in, weights_rec=w_rec, weights_out=w_out, dash_mem=dash(h.tau_mem, 8),
                    dash_syn=dash(h.tau_syn, 8), dash_syn_2=dash(h.tau_syn, 8), dash_mem_out=dash(o.tau_mem, 3),
                    dash_syn_out=dash(o.tau_syn, 3), threshold=np.full(8, int(scale), np.int16),
                    threshold_out=np.full(3, int(scale), np.int16), bias=np.zeros(8, np.int16),
                    bias_out=np.zeros(3, np.int16), weight_shift_in=s_in, weight_shift_rec=s_rec,
                    weight_shift_out=s_out, aliases=[[] for _ in range(8)], dt=graph.dt)


def test_finetune_a_spec_through_the_engine():
    graph = tiny_graph()
    spec = hand_mapped(graph)
    split = split_inputs(width=6, steps=STEPS, train=48, validation=40, held_out=40, density=0.25, seed=0)
    config = FinetuneConfig(epochs=2, batch=16, lr={"weights": 0.5, "thresholds": 5.0, "decays": 0.0, "biases": 1.0})
    out = finetune_xylo(spec, graph, split, hidden={"hidden": np.arange(8)}, output="out", config=config)
    r = out.record
    json.dumps(r.as_dict())
    assert r.steps == 2 * 3 and len(r.validation) == 3
    assert kept_by_the_rule(r.validation, r.kept_epoch)
    # the record's held-out figure is the exported spec's, run by the emulator
    from snncc.measure.agreement import argmax_agreement
    from snncc.finetune.teacher import run_teacher

    teacher = run_teacher(graph, split.x[split.held_out], ("hidden", "out"), voltage=False)
    mine = argmax_agreement(teacher.counts, emulate(out.spec, split.x[split.held_out]).counts)
    assert mine.as_dict() == r.held_out_after
    assert out.metadata()["finetuned"] and out.metadata()["seed"] == 0
