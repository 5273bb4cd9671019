import json

import numpy as np
import pytest

from snncc_test_helpers import run_cli

from .helpers import chain, paper_rsnn

bundle_mod = pytest.importorskip("snncc.targets.loihi.bundle.write")


@pytest.fixture
def rsnn_bundle(tmp_path):
    path = tmp_path / "rsnn.h5"
    bundle_mod.write_bundle(paper_rsnn(scale=20.0), path)
    return path


def test_map_bundle_json_and_plot(rsnn_bundle, tmp_path, capsys):
    png = tmp_path / "map.png"
    code, out, err = run_cli(["map", rsnn_bundle, "--json", "--plot", png], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["n_cores"] == 3 and d["lower_bound"] == 3 and d["n_chips"] == 1
    assert {"core", "chip", "neurons", "input_axons", "output_axons", "synapse_bits", "layers"} <= set(d["cores"][0])
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size > 5000


def test_map_bundle_text(rsnn_bundle, capsys):
    code, out, _ = run_cli(["map", rsnn_bundle], capsys)
    assert code == 0 and "lower bound 3" in out and "binding constraint" in out


def test_map_json_revalidates_independently(tmp_path, capsys):
    """The printed JSON, re-checked against the limits from the network alone."""
    from snncc.targets.loihi.mapping.resources import LOIHI1

    from .recheck import assert_valid

    net = chain([300, 1500, 40], seed=3, rec=(1,))
    path = tmp_path / "net.h5"
    bundle_mod.write_bundle(net, path)
    code, out, err = run_cli(["map", path, "--json"], capsys)
    assert code == 0, err
    from snncc.targets.loihi.bundle.read import read_bundle

    assert_valid(read_bundle(path), json.loads(out), LOIHI1)


def test_map_model_file_is_lowered_first(small_rsnn_checkpoint, capsys):
    pytest.importorskip("snncc.targets.loihi.lowering.registers")
    code, out, err = run_cli(["map", small_rsnn_checkpoint, "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["n_cores"] >= 1 and d["totals"]["neurons"] == 32 + 28


def test_map_impossible_network_one_line_naming_limit_and_layer(tmp_path, capsys):
    n = 4097
    w_rec = np.zeros((n, n), np.int16)
    w_rec[0, :] = 2
    from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

    from .helpers import layer

    net = LoihiNetwork([LoihiLayer("input", "input", 2),
                        layer("loop", n, np.full((n, 2), 2), kind="dense_rec", w_rec=w_rec)], t_sample=4)
    path = tmp_path / "wide.h5"
    bundle_mod.write_bundle(net, path)
    code, out, err = run_cli(["map", path], capsys)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "input axons" in lines[0] and "loop" in lines[0] and str(path) in lines[0]


def test_map_missing_file(tmp_path, capsys):
    code, _, err = run_cli(["map", tmp_path / "nope.h5"], capsys)
    assert code == 2 and "does not exist" in err and len(err.strip().splitlines()) == 1


def test_report_energy_random_inputs_json(rsnn_bundle, capsys):
    code, out, err = run_cli(["report", rsnn_bundle, "--energy", "--samples", "2", "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    est = d["estimate"]
    assert est["label"].startswith("ESTIMATE") and "SYNTHETIC" in est["inputs"]
    assert est["paper_measurement"]["energy_uj_per_sample"] == 71.0 and est["samples"] == 2


def test_report_energy_from_npy_with_limit(rsnn_bundle, tmp_path, capsys):
    x = (np.random.default_rng(1).random((3, 100, 24)) < 0.1).astype(np.uint8)   # 24 channels: copies tiled
    npy = tmp_path / "x.npy"
    np.save(npy, x)
    code, out, err = run_cli(["report", rsnn_bundle, "--energy", "--input", npy, "--limit", "2"], capsys)
    assert code == 0, err
    assert "ESTIMATE" in out and "paper, measured" in out and "tiled x2" in out and "padded" in out


def test_report_bad_inputs(rsnn_bundle, tmp_path, capsys):
    code, out, err = run_cli(["report", rsnn_bundle], capsys)          # without --energy: the resource report
    assert code == 0 and "core" in out.lower(), err
    code, _, err = run_cli(["report", rsnn_bundle, "--samples", "3"], capsys)
    assert code == 2 and "--samples" in err and "--energy" in err
    bad = tmp_path / "bad.npy"
    bad.write_bytes(b"not numpy")
    code, _, err = run_cli(["report", rsnn_bundle, "--energy", "--input", bad], capsys)
    assert code == 2 and "bad.npy" in err and len(err.strip().splitlines()) == 1
    np.save(tmp_path / "w.npy", np.zeros((2, 10, 5)))
    code, _, err = run_cli(["report", rsnn_bundle, "--energy", "--input", tmp_path / "w.npy"], capsys)
    assert code == 2 and "channels" in err
