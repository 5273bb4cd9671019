"""Validation fails loudly: banned operators, unused inputs, numeric mismatches; check() reports figures."""

from __future__ import annotations

import numpy as np
import onnx
import onnx.helper as oh
import pytest
from onnx import TensorProto

from snncc.errors import InternalError, SnnccError
from snncc.targets.jetson import target
from snncc.targets.jetson.export import ExportedModel, export_sequence, export_step
from snncc.targets.jetson.plan import plan_graph
from snncc.targets.jetson.validate import check_structure, validate_export
from tests.jetson.helpers import STEPS, seeded_inputs


def tiny_model(nodes, inputs, outputs) -> ExportedModel:
    graph = oh.make_graph(nodes, "g", inputs, outputs)
    model = oh.make_model(graph, opset_imports=[oh.make_opsetid("", 13)], ir_version=8)
    return ExportedModel(model.SerializeToString(), [i.name for i in inputs], [o.name for o in outputs], {})


def vi(name):
    return oh.make_tensor_value_info(name, TensorProto.FLOAT, ["B", 3])


def test_sequence_operators_are_refused():
    model = tiny_model([oh.make_node("SequenceConstruct", ["x"], ["s"]), oh.make_node("ConcatFromSequence", ["s"], ["y"], axis=0)],
                       [vi("x")], [vi("y")])
    with pytest.raises(SnnccError, match="SequenceConstruct"):
        check_structure(model, "model.onnx")


def test_unused_graph_input_is_refused():
    model = tiny_model([oh.make_node("Relu", ["x"], ["y"])], [vi("x"), vi("unused")], [vi("y")])
    with pytest.raises(SnnccError, match="'unused' is not used"):
        check_structure(model, "step.onnx")


def test_a_wrong_weight_in_the_export_is_caught(graphs):
    plan = plan_graph(graphs["rsnn"].copy())
    steps = 12
    seq, step = export_sequence(plan, steps, 13), export_step(plan, 13)
    proto = seq.proto
    for init in proto.graph.initializer:
        if list(init.dims) == [12, 20]:  # W_in (in, out) as stored
            w = onnx.numpy_helper.to_array(init).copy()
            w[:, :10] *= -1.0
            init.CopyFrom(onnx.numpy_helper.from_array(w, init.name))
    broken = ExportedModel(proto.SerializeToString(), seq.inputs, seq.outputs, seq.dynamic_axes)
    with pytest.raises(InternalError, match="model.onnx.*spike agreement"):   # a bug in the export, not bad input
        validate_export(plan, steps, broken, step)


def test_lstm_score_mismatch_is_caught(graphs):
    plan = plan_graph(graphs["lstm"].copy())
    seq, step = export_sequence(plan, STEPS, 13), export_step(plan, 13)
    proto = step.proto
    for init in proto.graph.initializer:
        if len(init.dims) == 1 and init.dims[0] == 5:  # the fc bias
            b = onnx.numpy_helper.to_array(init) + 0.5
            init.CopyFrom(onnx.numpy_helper.from_array(b.astype(np.float32), init.name))
    broken = ExportedModel(proto.SerializeToString(), step.inputs, step.outputs, step.dynamic_axes)
    with pytest.raises(InternalError, match="step.onnx.*scores differ"):
        validate_export(plan, STEPS, seq, broken)


def test_check_reports_accuracy_agreement_and_fp16(graphs):
    g = graphs["rsnn"].copy()
    g.metadata["recording_length_s"] = STEPS * g.dt   # check compiles model.onnx for 30 steps, not 270: cheaper
    x = seeded_inputs(g, 10, 12, seed=31)
    labels = np.arange(10) % 5
    rec = target.check(g, x, labels, {})
    assert rec.samples == 10 and rec.steps == 12
    assert rec.details["spike_agreement"] >= 0.999 and rec.argmax_agreement == 1.0
    assert rec.accuracy["float"] == rec.accuracy["artefact"]
    assert rec.details["fp16"]["spike_flips"] >= 0 and rec.details["fp16"]["accuracy"] is not None
    d = rec.as_dict()
    assert d["details"]["validation"]["sequence"]["spike_agreement"] >= 0.999
    from rich.console import Console

    console = Console(record=True, width=120)
    rec.render_text(console)
    assert "output spike agreement" in console.export_text()


def test_check_names_its_data_and_says_when_it_is_synthetic(artefacts):
    """``check(data=, synthetic=)`` are honoured: a data error names the file, synthetic data is said so (one
    artefact for the three checks: the session's, lowered once from the same graph)."""
    g, _, written = artefacts["rsnn"]
    x = seeded_inputs(g, 4, 12, seed=5)
    rec = target.check(g, x, np.arange(4) % 5, {}, artefact=written, data="d.npz", synthetic=True)
    assert "the data set is synthetic: these accuracies are not the paper's" in rec.notes
    assert not any("synthetic" in n for n in
                   target.check(g, x, np.arange(4) % 5, {}, artefact=written, data="d.npz").notes)
    with pytest.raises(SnnccError) as err:
        target.check(g, x, np.arange(3), {}, artefact=written, data="d.npz")
    assert err.value.line() == "d.npz: labels: 3 labels for 4 samples"
