"""snncc data nir: SYNTHETIC letters in the NIR paper's layout, labelled, read by check --data as a labelled set
(marked SYNTHETIC in the record)."""

from __future__ import annotations

import json

import numpy as np

from snncc_test_helpers import run_cli


def test_the_letters_are_labelled_nir_layout_data(tmp_path, capsys, shared_nir):
    out = tmp_path / "letters.npz"
    code, stdout, err = run_cli(["data", "nir", "-o", out, "-n", "14", "--json"], capsys)
    assert code == 0, err
    record = json.loads(stdout)
    assert record["samples"] == 14 and record["synthetic"] and record["classes"][0] == "Space"
    with np.load(out, allow_pickle=False) as z:
        assert z["inputs"].shape == (14, 256, 12) and set(np.unique(z["labels"])) <= set(range(7))
    # --time-steps 20: a 20-step ONNX export instead of 256 (~10x cheaper); the 256-step letters run through step.onnx
    code, stdout, err = run_cli(["check", shared_nir / "braille_noDelay_noBias_subtract.nir", "--dt", "1e-4",
                                 "--reset", "subtract", "--target", "jetson", "--time-steps", "20", "--data", out,
                                 "--json"], capsys)
    assert code == 0, err
    checked = json.loads(stdout)
    assert checked["accuracy"] is not None and "SYNTHETIC" in checked["inputs"] and checked["samples"] == 14
    # the same file feeds emulate (--data, as check and compare name it): the float graph counts its output spikes
    code, _, err = run_cli(["emulate", shared_nir / "braille_noDelay_noBias_subtract.nir", "--data", out,
                            "-o", tmp_path / "float.npz"], capsys)
    assert code == 0, err
    with np.load(tmp_path / "float.npz") as z:
        assert z["output_spikes"].shape == (14, 256, 7)
        assert (z["counts"] == z["output_spikes"].sum(axis=1)).all() and (z["prediction"] == z["counts"].argmax(1)).all()
    code, _, err = run_cli(["data", "nir", "-o", tmp_path / "letters.npy"], capsys)
    assert code == 2 and "name the file .npz" in err
