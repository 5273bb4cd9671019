"""``snncc map`` / ``report`` of a Xylo artefact: the real-time verdict leads with the expected load, the usage
plot names the artefact and its chip and its labels read horizontally."""

from __future__ import annotations

import numpy as np

from snncc.targets.xylo.estimate.real_time import real_time
from snncc.targets.xylo.estimate.usage import usage_of
from tests.xylo.lowering.test_design_rules import small_spec


def test_the_verdict_states_the_expected_load_first_and_the_worst_case_beside_it():
    spec = small_spec(n=400, n_in=16, n_out=8)
    rt = real_time(spec, dt=1e-3, rates={"input": 0.05, "hidden": 0.02, "output": 0.01}).as_dict()
    assert rt["real_time_expected"] and not rt["real_time"] and rt["margin_expected"] > 1 > rt["margin"]
    line = real_time(spec, dt=1e-3, rates={"input": 0.05, "hidden": 0.02, "output": 0.01}).line()
    assert line.startswith("at the event rates of the given inputs: runs in real time")
    assert line.index("margin") < line.index("worst case") and line.endswith("not real time (ESTIMATE, not measured)")
    slow = real_time(spec, dt=1e-6, rates={"input": 0.5, "hidden": 0.5, "output": 0.5}).line()
    assert "does NOT run in real time" in slow.split("worst case")[0]


def test_the_usage_plot_has_a_title_and_horizontal_labels(tmp_path):
    from snncc.targets.xylo.spec import XyloSpec

    spec = XyloSpec(**{**small_spec(), "aliases": [[] for _ in range(10)], "dt": 1e-3})
    usage = usage_of(spec, source=str(tmp_path / "net.xylo"), chip="syns61201", rates={}, rates_from="nothing")
    fig = usage.figure()
    ax = fig.axes[0]
    assert ax.get_title() == "Xylo usage of net.xylo (compiled for Xylo Audio 2, syns61201)"
    labels = ax.get_yticklabels()
    assert [t.get_text() for t in labels][:2] == ["input channels", "hidden neurons"]
    assert all(t.get_rotation() == 0 for t in labels) and not any(t.get_text() for t in ax.get_xticklabels()
                                                                   if t.get_rotation())
    assert any("compiled for" in t.get_text() for t in ax.get_legend().get_texts())
    usage.plot(tmp_path / "usage.png")
    assert (tmp_path / "usage.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    np.testing.assert_equal(len(ax.patches), 3 * len(labels))
