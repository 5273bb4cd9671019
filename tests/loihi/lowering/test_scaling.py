"""The scale-rule screen: each flag carries its kind beside the message it prints."""

from __future__ import annotations

import numpy as np

from snncc.targets.loihi.bundle.portability import NetxGap
from snncc.targets.loihi.lowering.scaling import CandidateMeasure, Flag, FlagKind, Screen, choose, screen
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
    g, rec = choose(graph, "split", measure=lambda g, r: CandidateMeasure(0.0), calibration="none")
    assert rec.rule == "split" and "split exponents on ['w_rec']" in rec.reason


def test_the_calibration_record_keeps_plain_messages():
    graph = _outlier_graph()
    _, rec = choose(graph, "auto", measure=lambda g, r: CandidateMeasure(float(r.rule != "fine")), calibration="none")
    flagged = rec.calibration["flagged"]
    assert all(isinstance(v, str) for v in flagged.values()) and flagged["w_rec"].startswith("max|W| is ")
    assert f"w_rec: {flagged['w_rec']}" in rec.reason


def _gap(by_rule):
    return [NetxGap("per-synapse weight exponents" if by_rule else "always-on bias sources", "/layer/1", by_rule)]


def _measure(errors, silent=(), float_silent=False, model_gap=False):
    """A stand-in measurement: ``errors`` by rule, outputs silent for the rules in ``silent``."""
    def measure(g, r):
        key = r.rule if r.fine_step in (None, 1.0) else f"fine x{r.fine_step:g}"
        gaps = (_gap(True) if r.rule in ("split", "fine") else []) + (_gap(False) if model_gap else [])
        return CandidateMeasure(None if float_silent else errors.get(key, 0.5), outputs_silent=key in silent or
                                float_silent, float_silent=float_silent, gaps=gaps)
    return measure


def test_auto_never_chooses_a_candidate_whose_outputs_are_silent():
    graph = _outlier_graph()
    _, rec = choose(graph, "auto", _measure({"global": 0.0, "per-layer": 0.3}, silent={"global"}), "none")
    assert rec.rule == "per-layer" and rec.calibration["outputs_silent"] == ["global"], rec.reason
    assert "left out (outputs silent" in rec.reason


def _compare(shares, samples=256):
    """A stand-in second look: argmax agreement ``shares`` by rule, each as (share, low, high)."""
    def compare(records):
        return {"samples": samples, "inputs": f"{samples} stand-in samples",
                "agreement": {name: dict(zip(("share", "low", "high"), shares[records[name].rule]))
                              for name in records} if samples else {},
                "cores": {name: 1 for name in records}}
    return compare


def test_auto_keeps_the_paper_rule_unless_another_measures_better_beyond_the_interval():
    graph = _outlier_graph()
    errors = {"global": 0.3, "per-layer": 0.2, "fine": 0.01}
    overlapping = _compare({"global": (0.70, 0.64, 0.75), "per-layer": (0.80, 0.74, 0.85)})
    _, rec = choose(graph, "auto", _measure(errors), "none", compare=overlapping)
    assert rec.rule == "global" and set(rec.calibration["errors"]) == {"global", "per-layer"}   # portable only
    assert "not a better agreement beyond the 95 % interval on 256 samples" in rec.reason
    assert "would gain +10.0 points" in rec.reason and rec.calibration["significance"]["chosen"] == "global"
    beyond = _compare({"global": (0.70, 0.64, 0.75), "per-layer": (0.85, 0.80, 0.89)})
    _, rec = choose(graph, "auto", _measure(errors), "none", compare=beyond)
    assert rec.rule == "per-layer" and "measures better beyond the 95 % interval" in rec.reason
    _, rec = choose(graph, "auto", _measure(errors), "none", compare=_compare({}, samples=0))
    assert rec.rule == "global" and "on the calibration inputs only" in rec.reason     # too large to look again
    _, rec = choose(graph, "auto", _measure({"global": 0.1, "per-layer": 0.2}), "none", compare=beyond)
    assert rec.rule == "global" and rec.calibration["significance"] is None          # nothing measured better


def test_auto_measures_every_rule_when_the_model_needs_more_and_says_what_fine_changes():
    graph = _outlier_graph()
    errors = {"global": 0.3, "per-layer": 0.2, "fine": 0.01}
    beyond = _compare({"global": (0.70, 0.64, 0.75), "fine": (0.90, 0.86, 0.93)})
    _, rec = choose(graph, "auto", _measure(errors, model_gap=True), "none", compare=beyond)
    assert rec.rule == "fine" and rec.fine_step == 1.0 and rec.calibration["best_netx_rule"] == {
        "rule": "per-layer", "error": 0.2, "agreement": None}     # this stub measures no agreement
    assert "rounds the decay registers to nearest (the paper truncates" in rec.reason
    assert not any(name.startswith("fine x") for name in rec.calibration["errors"])   # no noise-fitting sweep


def test_a_model_silent_in_float_is_not_measured_and_all_silent_rules_are_refused():
    graph = _outlier_graph()
    _, rec = choose(graph, "auto", _measure({}, float_silent=True), "none")
    assert rec.rule == "global" and "silent" in rec.reason and set(rec.calibration["errors"].values()) == {None}
    everything = {"global", "per-layer", "split", "fine"}
    import pytest

    from snncc.errors import SnnccError

    with pytest.raises(SnnccError, match="silent"):
        choose(graph, "auto", _measure({}, silent=everything), "none")


def test_a_network_too_large_for_the_second_look_keeps_the_paper_rule_without_measuring_others():
    graph = _outlier_graph()
    seen = []

    def measure(g, r):
        seen.append(r.rule)
        return CandidateMeasure(0.3 if r.rule == "global" else 0.01)

    _, rec = choose(graph, "auto", measure, "none", no_second_look="1,000,000 synapses x 100 steps allow 20 samples")
    assert rec.rule == "global" and seen == ["global"] and "none was measured" in rec.reason
    assert "allow 20 samples" in rec.reason and set(rec.calibration["errors"]) == {"global"}
    # a paper rule that cannot run (outputs silent) still falls back to the others
    _, rec = choose(graph, "auto", _measure({"global": 0.0, "per-layer": 0.3}, silent={"global"}), "none",
                    no_second_look="too large")
    assert rec.rule == "per-layer"
