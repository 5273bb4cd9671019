"""snncc check measures the written Loihi bundle: the file compile wrote, or the one compile would
write, run again in the emulator; refused when it came from another model; silent models reported as such;
the authors' RSNN takes its 24 event channels (the bundle's input copies tiled by snncc)."""

from __future__ import annotations

import hashlib
import json

import h5py
import numpy as np
import pytest
import torch

from snncc.ir.serialize import save_graph
from snncc_test_helpers import run_cli
from tests.loihi.helpers import small_graph

AGREEMENT = ["--limit", "12", "--json"]


def _weights(path, seed=2):
    """An authors'-layout weight list: 48 input axons (24 event channels x 2 copies) -> 24 -> 28."""
    g = torch.Generator().manual_seed(seed)
    torch.save([torch.randn(48, 24, generator=g) * 0.5, torch.randn(24, 28, generator=g) * 0.5,
                torch.randn(24, 24, generator=g) * 0.1], path)
    return path


def _compile(capsys, model, out, *extra):
    code, stdout, err = run_cli(["compile", model, "--target", "loihi", "-o", out, "--json", *extra], capsys)
    assert code == 0, err
    return json.loads(stdout)


def _check(capsys, model, *extra):
    code, stdout, err = run_cli(["check", model, *extra], capsys)
    assert code == 0, err
    return json.loads(stdout)


def _one_line(code, err, needle):
    assert code == 2 and needle in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


def test_check_measures_what_compile_wrote_with_the_same_hash_and_figures(tmp_path, capsys, th1_params):
    weights = _weights(tmp_path / "w.pt")
    out = tmp_path / "m.net"
    report = _compile(capsys, weights, out, "--params", th1_params)
    assert report["sha256"] == hashlib.sha256(out.read_bytes()).hexdigest()
    here = _check(capsys, weights, "--params", th1_params, *AGREEMENT)
    written = _check(capsys, weights, "--params", th1_params, "--artefact", out, *AGREEMENT)
    a, b = here.pop("artefact"), written.pop("artefact")
    assert a["sha256"] == b["sha256"] == report["sha256"]          # check compiled exactly as compile did
    assert a["compiled_by_check"] and a["path"] is None and not b["compiled_by_check"] and b["path"] == str(out)
    assert here == written                                          # the same figures, measured twice
    details = written["details"]
    assert details["scale_rule"] == report["scale_rule"] and details["candidates"] == report["scale_candidates"]
    assert written["samples"] == 12 and written["steps"] == report["t_sample"] == 270   # the model's own length
    assert set(written["liveness"]) == {"float", "loihi"} and set(written["liveness"]["loihi"]) == {"hidden", "out"}


def test_check_runs_the_file_it_is_given(tmp_path, capsys, authors_layout_bundle):
    """A bundle changed after compile (same source hash) is measured as it is, not as compile recorded it."""
    import shutil

    weights, th1_params, compiled = authors_layout_bundle
    out = tmp_path / "m.net"
    shutil.copy(compiled, out)                                      # the session's bundle, edited as a copy
    before = _check(capsys, weights, "--params", th1_params, "--artefact", out, *AGREEMENT)
    with h5py.File(out, "r+") as f:
        w = f["layer/2/weight"]
        w[...] = np.asarray(w)[::-1]                                # the readout's rows in reverse order
    after = _check(capsys, weights, "--params", th1_params, "--artefact", out, *AGREEMENT)
    assert after["artefact"]["sha256"] != before["artefact"]["sha256"]
    assert after["details"]["layer_spike_agreement"]["out"] != before["details"]["layer_spike_agreement"]["out"]
    assert any("another network" in n and "layer 2 weight" in n for n in after["notes"]), after["notes"]
    assert [s["key"] for s in after["stages"]] == ["emulator"] and after["stages"][0]["cause"] is None
    assert set(after["causes"].values()) == {None}                    # no breakdown for a foreign network


def test_check_refuses_what_does_not_belong(tmp_path, capsys, authors_layout_bundle):
    weights, th1_params, out = authors_layout_bundle
    other = _weights(tmp_path / "other.pt", seed=5)
    code, _, err = run_cli(["check", other, "--params", th1_params, "--artefact", out], capsys)
    _one_line(code, err, "source_sha256: was compiled from another model")
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--artefact", out, "--target", "jetson"], capsys)
    _one_line(code, err, "--target: the artefact is a loihi artefact, not jetson's")
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--artefact", out, "--scale", "global"], capsys)
    _one_line(code, err, "--scale: does not apply to a written artefact")
    junk = tmp_path / "junk.net"
    junk.write_bytes(b"not a bundle")
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--artefact", junk], capsys)
    _one_line(code, err, "not an artefact any installed target recognises")
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--artefact", tmp_path / "missing.net"], capsys)
    _one_line(code, err, "does not exist")
    assert out.exists() and junk.read_bytes() == b"not a bundle"    # nothing lost


def test_the_authors_rsnn_takes_its_24_event_channels(tmp_path, capsys, authors_layout_bundle):
    weights, th1_params, out = authors_layout_bundle
    events = (np.random.default_rng(0).random((3, 30, 24)) < 0.15).astype(np.uint8)
    np.save(tmp_path / "x24.npy", events)
    np.save(tmp_path / "x48.npy", np.tile(events, (1, 1, 2)))
    code, stdout, err = run_cli(["emulate", out, "-i", tmp_path / "x24.npy", "-o", tmp_path / "o24.npz", "--json"],
                                capsys)
    assert code == 0, err
    assert "tiled the data's 24 channels 2 times to the artefact's 48 inputs" in json.loads(stdout)["input_layout"]
    code, stdout, err = run_cli(["emulate", out, "-i", tmp_path / "x48.npy", "-o", tmp_path / "o48.npz"], capsys)
    assert code == 0 and "input:" not in stdout, err                # the flattened form: taken as it is, nothing said
    a, b = np.load(tmp_path / "o24.npz"), np.load(tmp_path / "o48.npz")
    assert np.array_equal(a["output_spikes"], b["output_spikes"]) and a["output_spikes"].any()
    labels = np.random.default_rng(1).integers(0, 28, 3)
    np.savez(tmp_path / "d.npz", inputs=events, labels=labels)
    rec = _check(capsys, weights, "--params", th1_params, "--artefact", out, "--data", tmp_path / "d.npz", "--json")
    assert "tiled the data's 24 channels 2 times" in rec["input_layout"] and rec["samples"] == 3
    assert set(rec["argmax"]) >= {"decided", "ties", "silent", "low", "high"}
    assert rec["accuracy"]["artefact"] == pytest.approx(np.mean(a["prediction"] == labels))   # the file, emulated


def test_a_silent_model_is_reported_silent_never_as_agreeing(tmp_path, capsys):
    """Weights 10^4 times too small: nothing spikes in float or on Loihi. No figure claims agreement."""
    quiet = tmp_path / "quiet.snnir"
    save_graph(small_graph(seed=1, scale=1e-4), quiet)
    report = _compile(capsys, quiet, tmp_path / "q.net", "--scale", "auto")
    assert report["validation"]["prediction_agreement"] is None
    assert report["validation"]["emulator_vs_trained"] == {"hidden": None, "out": None}
    assert set(report["scale_candidates"].values()) == {None} and "silent" in report["scale_reason"]
    assert len(report["warnings"]) == 1 and "likely cause: threshold or gain scale" in report["warnings"][0]
    assert any("'out' never spikes in float" in line for line in report["liveness"]["flagged"])
    rec = _check(capsys, quiet, *AGREEMENT)
    assert rec["argmax_agreement"] is None and rec["argmax"]["silent"] == 12 and rec["count_correlation"] is None
    assert rec["details"]["layer_spike_agreement"] == {"hidden": None, "out": None} and rec["total_points"] is None
    assert rec["causes"]["weights"] is None and rec["causes"]["saturation"] is None   # undefined, never 0
    assert rec["liveness"]["loihi"]["out"]["status"] == "silent" and len(rec["warnings"]) == 1
    code, stdout, _ = run_cli(["check", quiet, "--limit", "12"], capsys)
    assert code == 0 and "argmax agreement   undefined: outputs silent" in stdout and "100" not in stdout.split(
        "argmax agreement")[1].splitlines()[0]


def test_a_saturated_population_is_named(tmp_path, capsys):
    loud = tmp_path / "loud.snnir"
    graph = small_graph(seed=1, scale=1.0)
    graph.node("hidden").bias = np.full(graph.node("hidden").n, 50.0)   # a bias far above threshold: fires always
    save_graph(graph, loud)
    report = _compile(capsys, loud, tmp_path / "l.net", "--scale", "global")
    assert any("'hidden' spikes at every step it can in float" in line for line in report["liveness"]["flagged"])
    assert report["liveness"]["loihi"]["hidden"]["status"] == "saturated"


def test_portability_is_recorded_in_the_report_and_the_bundle(tmp_path, capsys):
    model = tmp_path / "m.snnir"
    save_graph(small_graph(seed=2, order="loihi"), model)     # the chip's own update order
    out = tmp_path / "m.net"
    report = _compile(capsys, model, out)
    assert report["portability"]["netx_runnable"] and report["portability"]["reasons"] == [], report["portability"]
    with h5py.File(out, "r") as f:
        stored = json.loads(f["snncc/portability"][()][0].decode())
        meta = json.loads(f["snncc/metadata"][()][0].decode())
    assert stored["netx_runnable"] and stored["line"].startswith("portable")
    assert meta["compile_options"] == {"timing": None, "scale": None, "allow_reset_change": False, "time_steps": None,
                                       "replicas": None}
    fine = _compile(capsys, model, tmp_path / "f.net", "--scale", "fine")
    assert not fine["portability"]["netx_runnable"] and fine["portability"]["reasons"][0]["by_rule"]
    assert fine["portability"]["line"].startswith("not runnable by netx as written: per-synapse weight exponents")
    authors = tmp_path / "a.snnir"                            # the authors' order: refractory 2 and delays
    save_graph(small_graph(seed=2), authors)
    needs = _compile(capsys, authors, tmp_path / "a.net", "--scale", "global")
    assert {g["feature"].split(" (")[0] for g in needs["portability"]["reasons"]} >= {"refDelay 2",
                                                                                    "recurrent synaptic delays"}
    code, stdout, _ = run_cli(["compile", model, "--target", "loihi", "-o", tmp_path / "f.net", "--scale", "fine"], capsys)
    assert code == 0 and "not runnable by netx as written" in stdout
