"""compile takes the target from -o's suffix where it names one (.net -> loihi, .snnir -> ir), refuses a
suffix that names another target than --target, and needs --target where the output names none."""

import zipfile
from pathlib import Path

import h5py
import numpy as np
import pytest

from snncc import api
from snncc.errors import SnnccError
from snncc.targets import get_target, output_suffixes
from snncc_test_helpers import run_cli

TWO_LIF = Path(__file__).resolve().parents[1] / "data" / "nir" / "two_lif_neurons.nir"


def test_each_file_target_declares_its_suffix():
    suffixes = output_suffixes()
    assert suffixes["ir"] == ".snnir" and suffixes["loihi"] == ".net" and "jetson" not in suffixes
    assert getattr(get_target("jetson"), "output_suffix", None) is None     # a directory names no target


def test_a_net_output_without_target_is_a_loihi_bundle_that_emulate_reads(tmp_path, capsys):
    out = tmp_path / "x.net"
    code, _, err = run_cli(["compile", TWO_LIF, "--dt", "1e-3", "-o", out], capsys)
    assert code == 0, err
    assert "snncc: note: target 'loihi' from the suffix '.net' of -o" in err
    assert h5py.is_hdf5(out)
    np.save(tmp_path / "x.npy", (np.random.default_rng(0).random((2, 30, 1)) < 0.2).astype(np.uint8))
    code, _, err = run_cli(["emulate", out, "--input", tmp_path / "x.npy", "-o", tmp_path / "e.npz"], capsys)
    assert code == 0 and (tmp_path / "e.npz").exists(), err


def test_an_snnir_output_without_target_is_the_ir(tmp_path, capsys):
    out = tmp_path / "x.snnir"
    code, _, err = run_cli(["compile", TWO_LIF, "--dt", "1e-3", "-o", out], capsys)
    assert code == 0 and zipfile.is_zipfile(out), err


@pytest.mark.parametrize("target, name, says", [
    ("ir", "x.net", "the suffix '.net' names the loihi target, not ir: name the output for ir (.snnir)"),
    ("loihi", "x.snnir", "the suffix '.snnir' names the ir target, not loihi: name the output for loihi (.net)"),
    ("jetson", "x.net", "the suffix '.net' names the loihi target, not jetson"),
    (None, "out", "-o does not say which target to compile for: pass --target (c, ir, jetson, loihi, xylo)"),
    (None, "x.h5", "or name the output by its suffix (.snnir -> ir, .net -> loihi, .xylo -> xylo)"),
])
def test_a_suffix_that_contradicts_or_names_no_target_is_one_line(tmp_path, capsys, target, name, says):
    out = tmp_path / name
    code, _, err = run_cli(["compile", TWO_LIF, "--dt", "1e-3", "-o", out] + (["--target", target] if target else []),
                           capsys)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith(f"snncc: error: {out}: --target: ") and says in lines[0], err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == []


def test_an_explicit_target_with_a_neutral_name_is_kept(tmp_path, capsys):
    out = tmp_path / "bundle.h5"
    code, _, err = run_cli(["compile", TWO_LIF, "--dt", "1e-3", "--target", "loihi", "-o", out], capsys)
    assert code == 0 and h5py.is_hdf5(out) and "from the suffix" not in err, err


def test_the_library_call_follows_the_same_rule(tmp_path):
    rec = api.compile(TWO_LIF, dt=1e-3, output=tmp_path / "x.net")
    assert rec.target == "loihi" and rec.as_dict()["target_rule"] == "the suffix '.net' of -o"
    assert api.compile(TWO_LIF, dt=1e-3, output=tmp_path / "y.snnir").target == "ir"
    with pytest.raises(SnnccError, match="names the ir target, not loihi"):
        api.compile(TWO_LIF, dt=1e-3, target="loihi", output=tmp_path / "z.snnir")
    assert not (tmp_path / "z.snnir").exists()
