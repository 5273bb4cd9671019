"""On the real graphs of tests/data/nir: ``snncc check`` on each graph and on each
artefact ``compile`` wrote reports the same hash and the same figures as compile; cnn_sinabs checks on both
targets; no compile or check reports agreement over silent outputs.

Inputs are seeded random spike trains (SYNTHETIC); few samples keep the suite fast (the defaults are for users).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from nir_graphs import run_cli

DATA = Path(__file__).resolve().parents[1] / "data" / "nir"
GRAPHS = ["braille_zero_2023.nir", "braille_noDelay_noBias_subtract.nir", "lif_norse.nir", "lif_rockpool.nir",
          "two_lif_neurons.nir"]        # braille_subgraph_2023.nir is refused in one line (test_real_graphs.py)
LIMIT = ["--limit", "4"]


def _load_flags(name):
    flags = ["--dt", "1e-4"] if name != "cnn_sinabs.nir" else []
    return flags + (["--reset", "subtract"] if "subtract" in name else [])


def _run(capsys, args):
    code, out, err = run_cli(args, capsys)
    assert code == 0, err
    return json.loads(out)


def _same_as_compile(capsys, name, target, out, compile_flags, compiled=None):
    """compile, check the model, check the written artefact: one hash, one set of figures. ``compiled``: the
    (artefact, JSON report) of that compile where a session fixture already ran it."""
    src = DATA / name
    if compiled is None:
        report = _run(capsys, ["compile", src, "--target", target, "-o", out, "--json", *_load_flags(name),
                               *compile_flags])
    else:
        out, report = compiled
    here = _run(capsys, ["check", src, "--target", target, "--json", *LIMIT, *_load_flags(name), *compile_flags])
    written = _run(capsys, ["check", src, "--artefact", out, "--json", *LIMIT, *_load_flags(name)])
    a, b = here.pop("artefact"), written.pop("artefact")
    assert a["sha256"] == b["sha256"] == report["sha256"], (name, target)
    assert b["target"] == target and b["path"] == str(out) and a["compiled_by_check"]
    assert here == written, name
    return report, written


def _never_over_silence(record, outputs_silent):
    """Agreement is a number only where the float outputs have a winner; silent outputs make it undefined."""
    share = record["argmax_agreement"] if "argmax_agreement" in record else record["prediction_agreement"]
    decisions = record["argmax"]
    if outputs_silent:
        assert share is None and decisions["silent"] == decisions["samples"], record
    else:
        assert share is None or decisions["decided"] > 0


@pytest.mark.parametrize("name", GRAPHS)
def test_check_reports_the_hash_and_figures_compile_reports(name, tmp_path, capsys):
    flags = ["--allow-reset-change"] if "subtract" in name else []
    report, rec = _same_as_compile(capsys, name, "loihi", tmp_path / "g.net", flags)
    details = rec["details"]
    assert details["scale_rule"] == report["scale_rule"] and details["candidates"] == report["scale_candidates"]
    float_silent = report["liveness"]["float"][list(report["liveness"]["float"])[-1]]["status"] == "silent"
    if float_silent:   # compile said so too, and claimed no agreement
        assert report["validation"]["prediction_agreement"] is None and len(report["warnings"]) == 1
    check_silent = rec["liveness"]["float"][list(rec["liveness"]["float"])[-1]]["status"] == "silent"
    _never_over_silence(rec, check_silent)
    assert rec["undecided_rule"].startswith("samples whose float output has no single winner")


def test_a_jetson_artefact_of_a_trained_graph_checks_like_compile(tmp_path, capsys):
    """Without labels (agreement) on the Jetson directory compile wrote: same hash, same figures."""
    report, rec = _same_as_compile(capsys, "braille_zero_2023.nir", "jetson", tmp_path / "bz_jetson",
                                   ["--time-steps", "20"])
    assert rec["samples"] == 4 and rec["target"] == "jetson"
    _never_over_silence(rec, False)


@pytest.mark.parametrize("target, flags", [("loihi", ["--time-steps", "12"]), ("jetson", ["--time-steps", "12"])])
def test_cnn_sinabs_checks_on_both_targets(target, flags, tmp_path, capsys, cnn_loihi_bundle):
    # Loihi: the session's bundle (compile --target loihi --time-steps 12 --json, as compiled here before)
    compiled = cnn_loihi_bundle(capsys) if target == "loihi" else None
    out = compiled[0] if compiled else tmp_path / "cnn_jetson"
    report, rec = _same_as_compile(capsys, "cnn_sinabs.nir", target, out, flags, compiled)
    assert rec["samples"] == 4
    _never_over_silence(rec, False)
    assert set(rec["liveness"]["float"]) == {"1", "3", "6", "10", "12"}
    frames = (np.random.default_rng(0).random((2, 12, 2, 34, 34)) < 0.05).astype(np.uint8)   # N-MNIST-shaped
    np.save(tmp_path / "frames.npy", frames)
    np.save(tmp_path / "flat.npy", frames.reshape(2, 12, -1))
    verb = ["emulate", out] if target == "loihi" else ["run", out]
    got = {}
    for kind in ("frames", "flat"):
        code, stdout, err = run_cli([*verb, "-i", tmp_path / f"{kind}.npy", "-o", tmp_path / f"{kind}.npz", "--json"],
                                    capsys)
        assert code == 0, err
        assert (json.loads(stdout)["input_layout"] is not None) == (kind == "frames")
        got[kind] = np.load(tmp_path / f"{kind}.npz")["output_spikes"]
    assert np.array_equal(got["frames"], got["flat"])
    np.savez(tmp_path / "d.npz", inputs=frames, labels=np.array([1, 7]))
    labelled = _run(capsys, ["check", DATA / "cnn_sinabs.nir", "--artefact", out, "--data", tmp_path / "d.npz",
                             "--json"])
    assert "read frames of 2x34x34 as 2312 channels" in labelled["input_layout"] and labelled["samples"] == 2


def test_a_graph_that_needs_what_netx_lacks_names_it_and_the_best_netx_bundles_agreement(tmp_path, capsys):
    """braille_zero_2023 places its biases on the current (always-on input axons): no rule is netx-runnable as
    written, so the default bundle is the best measured one, and the best netx rule's figures stand beside it."""
    src, out = DATA / "braille_zero_2023.nir", tmp_path / "bz.net"
    report = _run(capsys, ["compile", src, "-o", out, "--json", *_load_flags("braille_zero_2023.nir")])
    port = report["portability"]
    assert not port["netx_runnable"] and port["line"].startswith("not runnable by netx as written: always-on input")
    assert {"feature": "always-on input axons (netx does not know them; its driver must hold them at 1)",
            "where": "/layer/0/alwaysOn", "by_rule": False} in port["reasons"]
    best = port["best_netx_rule"]
    assert best["rule"] in ("global", "per-layer") and best["error"] > port["chosen_error"]
    assert best["agreement"]["samples"] == 8 and best["agreement"]["decided"] + best["agreement"]["ties"] \
        + best["agreement"]["silent"] == 8
    assert port["chosen_agreement"]["samples"] == 8
    code, stdout, err = run_cli(["compile", src, "-o", tmp_path / "again.net", *_load_flags("braille_zero_2023.nir")],
                                capsys)
    assert code == 0, err
    # printed: the rule and its calibration error; its 8-sample agreement stays in the record (no near-empty interval)
    assert f"best bundle under a rule netx can run (the model's own needs aside): '{best['rule']}'" in stdout
    assert "argmax agreement with the float model on the calibration inputs" not in stdout
