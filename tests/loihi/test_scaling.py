"""The scale-rule screen: each flag carries its kind beside the message it prints."""

from __future__ import annotations

import numpy as np

from snncc.targets.loihi.lowering.scaling import Flag, FlagKind, Screen, choose, screen
from tests.loihi.helpers import small_graph


def _outlier_graph():
    graph = small_graph(seed=8, n_h=30)
    v = graph.node("w_rec").weight
    v[0, 1] = 100 * float(np.median(np.abs(v)))        # one outlier: 100x the median
    return graph


def test_an_outlier_is_flagged_by_kind_with_the_message_unchanged():
    sc = screen(_outlier_graph())
    flag = sc.flagged["w_rec"]
    assert flag.kind is FlagKind.OUTLIERS and sc.of_kind(FlagKind.OUTLIERS) == {"w_rec"}
    assert flag.message.startswith("max|W| is ") and flag.message.endswith("x the median |W|")
    assert str(flag) == flag.message and sc.messages()["w_rec"] == flag.message


def test_split_follows_the_kind_not_the_wording():
    """A flag worded like an outlier but of another kind does not get split exponents."""
    sc = Screen({"w_rec": Flag(FlagKind.LOW_RANGE, "max|W| is worded like an outlier")}, True)
    assert sc.of_kind(FlagKind.OUTLIERS) == set()
    graph = _outlier_graph()
    g, rec = choose(graph, "split", measure=lambda g, r: 0.0, calibration="none")
    assert rec.rule == "split" and "split exponents on ['w_rec']" in rec.reason


def test_the_calibration_record_keeps_plain_messages():
    graph = _outlier_graph()
    _, rec = choose(graph, "auto", measure=lambda g, r: float(r.rule != "fine"), calibration="none")
    flagged = rec.calibration["flagged"]
    assert all(isinstance(v, str) for v in flagged.values()) and flagged["w_rec"].startswith("max|W| is ")
    assert f"w_rec: {flagged['w_rec']}" in rec.reason
