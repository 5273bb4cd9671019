"""snncc compile/emulate/check for Loihi through the CLI: outputs, JSON, one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from snncc_test_helpers import run_cli


@pytest.fixture
def weights(tmp_path, th1_params):
    g = torch.Generator().manual_seed(2)
    path = tmp_path / "w.pt"
    torch.save([torch.randn(48, 24, generator=g) * 0.5, torch.randn(24, 28, generator=g) * 0.5,
                torch.randn(24, 24, generator=g) * 0.1], path)
    return path


def test_compile_emulate_check(tmp_path, capsys, weights, th1_params):
    out = tmp_path / "m.net"
    code, stdout, err = run_cli(["compile", weights, "--params", th1_params, "--target", "loihi", "-o", out], capsys)
    assert code == 0, err
    assert "netx" in stdout and "refDelay" in stdout and out.exists()
    code, stdout, err = run_cli(["compile", weights, "--params", th1_params, "--target", "loihi", "-o", out, "--json",
                                 "--scale", "global"], capsys)
    rec = json.loads(stdout)
    assert rec["t_sample"] == 270 and rec["layers"][1]["iDecay"] == 2315 and rec["netx_compat"]   # the paper's rule
    assert not rec["portability"]["netx_runnable"] and "refDelay 2" in rec["portability"]["line"]
    rng = np.random.default_rng(0)
    np.save(tmp_path / "x.npy", rng.random((2, 30, 48)) < 0.1)
    code, stdout, err = run_cli(["emulate", out, "--input", tmp_path / "x.npy", "-o", tmp_path / "o.npz", "--json"], capsys)
    assert code == 0, err
    z = np.load(tmp_path / "o.npz")
    assert z["output_spikes"].dtype == np.uint8 and z["output_spikes"].shape == (2, 30, 28)
    data = tmp_path / "d.npz"
    np.savez(data, inputs=(rng.random((10, 60, 24)) < 0.1).astype(np.uint8), labels=rng.integers(0, 28, 10))
    code, stdout, err = run_cli(["check", weights, "--params", th1_params, "--target", "loihi", "--data", data,
                                 "--json", "--limit", "6"], capsys)
    assert code == 0, err
    rec = json.loads(stdout)
    assert rec["samples"] == 6 and set(rec["accuracy"]) == {"float", "artefact"}
    assert set(rec["details"]["accuracy_by_stage"]) == {"float_trained", "ir_quantized", "emulator_wide", "emulator"}
    assert [s["cause"] for s in rec["stages"]] == ["weights", "decays", "saturation"]
    assert rec["details"]["spike_agreement"]["loihi_order_vs_trained"]["hidden"] == 1.0   # exact timing: no order change
    code, stdout, err = run_cli(["check", weights, "--params", th1_params, "--data", data, "--limit", "4"], capsys)
    assert code == 0 and "the bundle as written, emulated" in stdout, err


@pytest.mark.parametrize("array, needle", [
    (np.zeros((5, 47), np.uint8), "channels"),
    (np.full((5, 48), 2, np.uint8), "binary"),
    (np.full((5, 48), np.nan), "NaN"),
])
def test_emulate_bad_input_one_line(tmp_path, capsys, authors_layout_bundle, array, needle):
    out = authors_layout_bundle[2]
    np.save(tmp_path / "x.npy", array)
    code, _, err = run_cli(["emulate", out, "--input", tmp_path / "x.npy", "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and needle in err and len(err.strip().splitlines()) == 1 and "x.npy" in err
    assert not (tmp_path / "o.npz").exists()


def test_compile_random_bytes_fails_cleanly(tmp_path, capsys):
    bad = tmp_path / "junk.pt"
    bad.write_bytes(np.random.default_rng(0).bytes(500))
    code, out, err = run_cli(["compile", bad, "--target", "loihi", "-o", tmp_path / "x.net"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and not (tmp_path / "x.net").exists()


@pytest.mark.parametrize("option, value", [("--scale", "bogus"), ("--timing", "late")])
def test_bad_scale_or_timing_is_one_line_and_writes_nothing(tmp_path, capsys, weights, th1_params, option, value):
    out = tmp_path / "x.net"
    code, _, err = run_cli(["compile", weights, "--params", th1_params, "--target", "loihi", "-o", out, option, value],
                           capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and option in err and not out.exists(), err
    data = tmp_path / "d.npz"
    np.savez(data, inputs=np.zeros((2, 10, 48), np.uint8), labels=np.zeros(2, np.int64))
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--data", data, option, value], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and option in err, err


def test_check_needs_a_target_with_check(tmp_path, capsys, weights, th1_params):
    data = tmp_path / "d.npz"
    np.savez(data, inputs=np.zeros((2, 10, 24), np.uint8), labels=np.zeros(2, np.int64))
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--target", "ir", "--data", data], capsys)
    assert code == 2 and "no check" in err
    np.savez(data, inputs=np.zeros((2, 10, 24), np.uint8))
    code, _, err = run_cli(["check", weights, "--params", th1_params, "--data", data], capsys)
    assert code == 2 and "labels" in err and len(err.strip().splitlines()) == 1


def test_emulate_stream_mode(tmp_path, capsys, authors_layout_bundle):
    out = authors_layout_bundle[2]
    np.save(tmp_path / "x.npy", (np.random.default_rng(3).random((3, 20, 48)) < 0.2).astype(np.uint8))
    code, stdout, err = run_cli(["emulate", out, "--input", tmp_path / "x.npy", "-o", tmp_path / "o.npz",
                                 "--stream", "--gap", "7", "--json"], capsys)
    assert code == 0, err
    assert json.loads(stdout)["mode"] == "stream"
    assert np.load(tmp_path / "o.npz")["output_spikes"].shape == (3, 20, 28)
