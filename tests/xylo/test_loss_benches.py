"""bench/studies/xylo_loss_by_layer.py and bench/studies/xylo_loss_sources.py swap one layer or one approximation at a time: where
nothing is swapped they must reproduce the unswapped runs exactly (the first checks it every run). Here on a small
replicated chain written by ``snncc compile``; and bench/studies/xylo_paired.py's paired comparison."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from snncc.ir.serialize import save_graph
from snncc.targets.xylo.emulation.emulator import emulate
from snncc.targets.xylo.lowering.lower import twin_counts
from xylo_models import lower_with
from snncc.targets.xylo.spec import XyloSpec
from snncc.targets.xylo.artefact.read import read_artefact
from snncc_test_helpers import load_bench, run_cli

from xylo_models import chain, spikes

QUICK = {"calibration_samples": 16, "time_steps": 40, "density": 0.15}


@pytest.fixture(scope="module")
def model():
    return chain(np.random.default_rng(5), n_in=6, n_hidden=12, n_out=3, beta=0.85, alpha_o=0.45, beta_o=0.7)


def test_layer_swaps_reproduce_the_artefact(tmp_path, capsys, model):
    """The float readout driven by the float hidden spikes is the float graph, the chip readout driven by the
    chip's hidden spikes is the emulator (one_seed exits otherwise); every copy of a replicated artefact is read."""
    bench = load_bench("studies/xylo_loss_by_layer")
    path = tmp_path / "chain.snnir"
    save_graph(model, path)
    out = tmp_path / "rep.xylo"
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--rule", "relayed", "--replicas", "2",
                            "--calibration-samples", "16", "--time-steps", "40", "-o", out], capsys)
    assert code == 0, err
    manifest = json.loads((out / "manifest.json").read_text())
    got = bench.one_seed(model, XyloSpec.load_npz(out / "spec.npz"), manifest, 24, 3, 0.15, steps=40)
    names = set(got["figures"])
    assert {"chip", "float readout, chip hidden (copies' mean)", "float readout, chip hidden copy 0",
            "float readout, chip hidden copy 1", "chip readout, float hidden"} == names
    assert all(a.argmax.samples == 24 and a.decided + a.argmax.ties + a.argmax.silent == 24
               for a in got["figures"].values())
    assert got["outputs"]["chip"].shape == (24, 3) and got["outputs"]["chip"].sum() > 0


def test_loss_sources_removes_one_approximation_at_a_time(model):
    """Relays 1x finer and uncapped are the twin itself; 100x finer changes the relays' registers only; the twin
    emulator runs an unrounded spec."""
    bench = load_bench("studies/xylo_loss_sources")
    low = lower_with(model, dict(QUICK, rule="relayed", replicas=2))
    x = spikes(np.random.default_rng(4), 16, 40, 6, 0.15)
    assert np.array_equal(twin_counts(bench.finer_relays(low, 1.0), low.timing, x),
                          twin_counts(low.twin, low.timing, x))
    fine = bench.finer_relays(low, 100.0)
    relay_cells = np.concatenate([np.arange(*r.neurons) for r in low.populations if r.role == "relay"])
    theta = fine.node("hidden").threshold
    assert np.allclose(theta[relay_cells] * 100, low.twin.node("hidden").threshold[relay_cells])
    others = np.setdiff1d(np.arange(theta.size), relay_cells)
    assert np.array_equal(theta[others], low.twin.node("hidden").threshold[others])
    unrounded = lower_with(model, dict(QUICK, rule="relayed", replicas=2, rounding="none",
                                  emulator=bench.twin_emulator(model.dt)))
    assert unrounded.spec["weights_rec"].dtype == np.float64
    assert twin_counts(unrounded.twin, unrounded.timing, x).shape == (16, 3)


def test_paired_comparison_counts_what_only_one_artefact_gets_right(tmp_path, capsys, model):
    """bench/studies/xylo_paired.py: an artefact against itself differs on no sample (p = 1); its chip counts are the emulator's
    read in the manifest's window; the exact McNemar p of a lopsided split is small, of an even one 1."""
    bench = load_bench("studies/xylo_paired")
    assert bench.mcnemar(0, 0) == 1.0 and bench.mcnemar(5, 5) == 1.0 and bench.mcnemar(20, 2) < 0.001
    path = tmp_path / "chain.snnir"
    save_graph(model, path)
    out = tmp_path / "one.xylo"
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--rule", "relayed", "--calibration-samples", "16",
                            "--time-steps", "40", "-o", out], capsys)
    assert code == 0, err
    result = tmp_path / "paired.json"
    argv = ["xylo_paired.py", str(out), str(out), "--model", str(path), "--samples", "30", "--steps", "40",
            "--density", "0.15", "--seeds", "1,2", "--out", str(result)]
    old, sys.argv = sys.argv, argv
    try:
        bench.main()
    finally:
        sys.argv = old
    rows = json.loads(result.read_text())["artefacts"]
    assert rows[1]["vs_first"] == {"only_this": 0, "only_first": 0, "mcnemar_p": 1.0}
    assert rows[0]["pooled"] == rows[1]["pooled"] and rows[0]["counted"] > 20
    x = spikes(np.random.default_rng(4), 5, 40, 6, 0.15)
    written = read_artefact(out)
    fed = np.pad(x, ((0, 0), (written.input_pad, max(written.input_pad, written.output_lag)), (0, 0))).astype(np.uint8)
    want = emulate(written.spec, fed).output_spikes[:, written.output_lag:written.output_lag + 40].sum(axis=1)
    assert np.array_equal(bench.chip_counts(written, x), want)
