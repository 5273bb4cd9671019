"""``check`` and ``agree`` read the written artefact and break the loss down by stage: a graph the integer grid
holds exactly loses nothing at any stage; the float reading of an artefact is the model's structure; labels give
accuracy beside agreement."""

from __future__ import annotations

import numpy as np

from c_test_graphs import spikes


def test_an_exactly_representable_graph_loses_nothing(tmp_path):
    from snncc.targets import get_target

    from c_test_graphs import exact_graph

    graph = exact_graph()
    target = get_target("c")
    target.lower(graph, {"rule": "per-neuron-16", "time_steps": 8}).write(tmp_path / "a")
    record = target.agree(graph, spikes(64, 8, 16, 0.4, 3), artefact=tmp_path / "a").as_dict()
    assert [s["key"] for s in record["stages"]] == ["weights", "decays", "grid", "artefact"]
    assert record["argmax_agreement"] == 1.0
    assert {k: v for k, v in record["causes"].items() if v is not None} == {"weights": 0.0, "decays": 0.0,
                                                                           "saturation": 0.0}
    assert record["possible"] == ["weights", "decays", "saturation"]


def test_labelled_check_reports_accuracy(tmp_path):
    from snncc.targets import get_target

    from c_test_graphs import random_graph

    graph = random_graph(9, n_out=4)
    x = spikes(40, 20, 5, 0.3, 4)
    labels = np.arange(40) % 4
    from snncc.targets.c.options import COptions

    report = get_target("c").check(graph, x, labels, COptions(rule="per-neuron", time_steps=20)).as_dict()
    assert set(report["accuracy"]) == {"float", "artefact"}
    assert all(s["accuracy"] is not None for s in report["stages"])
