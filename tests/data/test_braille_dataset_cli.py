"""The encoded data-set contract, the generator, and the ``snncc data`` commands end to end."""

from __future__ import annotations

import json

import numpy as np
import pytest

from snncc.data import formats
from snncc.data.binning import bin_events
from snncc.data.dataset_file import load_dataset, save_dataset
from snncc.data.letters import CLASSES
from snncc.data.sigma_delta import encode
from snncc.data.synth import generate
from snncc.errors import SnnccError

from .conftest import cli

META = {"kind": "events", "threshold": 1, "time_bin_size_ms": 5, "dt_s": 0.005, "n_steps": 270,
        "classes": list(CLASSES), "synthetic": True, "source": "x", "seed": 0}


def test_dataset_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    x = (rng.random((6, 270, 24)) < 0.1).astype(np.uint8)
    y = np.arange(6, dtype=np.int64)
    save_dataset(tmp_path / "d.npz", x, y, META)
    x2, y2, m2 = load_dataset(tmp_path / "d.npz")
    np.testing.assert_array_equal(x2, x)
    assert x2.dtype == np.uint8 and y2.dtype == np.int64 and m2 == META
    with np.load(tmp_path / "d.npz", allow_pickle=False) as z:
        assert sorted(z.files) == ["inputs", "labels", "meta"]
        assert isinstance(json.loads(str(z["meta"])), dict)
    f = np.zeros((3, 54, 12), np.float32)
    save_dataset(tmp_path / "f.npz", f, np.zeros(3, np.int64), dict(META, kind="frames", n_steps=54))
    assert load_dataset(tmp_path / "f.npz")[0].dtype == np.float32


@pytest.mark.parametrize("inputs, labels, meta, match", [
    (np.full((2, 270, 24), 2, np.uint8), np.zeros(2, np.int64), META, "binary"),
    (np.zeros((2, 270, 48), np.uint8), np.zeros(2, np.int64), META, "24 channels"),
    (np.zeros((2, 270, 24), np.float32), np.zeros(2, np.int64), META, "uint8"),
    (np.zeros((2, 270, 24), np.uint8), np.array([0, 27]), META, "0..26"),
    (np.zeros((2, 270, 24), np.uint8), np.zeros(2, np.int64), dict(META, n_steps=5), "n_steps"),
    (np.zeros((2, 270, 24), np.uint8), np.zeros(2, np.int64), dict(META, kind="spikes"), "kind"),
])
def test_dataset_validation(tmp_path, inputs, labels, meta, match):
    with pytest.raises(SnnccError, match=match):
        save_dataset(tmp_path / "bad.npz", inputs, labels, meta)
    assert not list(tmp_path.iterdir())  # nothing written
    # the same content smuggled in without save_dataset is refused on load
    with open(tmp_path / "raw.npz", "wb") as fh:
        np.savez(fh, inputs=inputs, labels=labels, meta=np.array(json.dumps(meta)))
    with pytest.raises(SnnccError, match=match):
        load_dataset(tmp_path / "raw.npz")


def test_dataset_refuses_pickles_and_garbage(tmp_path):
    with open(tmp_path / "p.npz", "wb") as fh:
        np.savez(fh, inputs=np.zeros((1, 2, 24), np.uint8), labels=np.zeros(1, np.int64),
                 meta=np.array([{"kind": "events"}], dtype=object))
    with pytest.raises(SnnccError, match="not a readable|meta"):
        load_dataset(tmp_path / "p.npz")
    (tmp_path / "g.npz").write_bytes(b"PK\x03\x04garbage")
    with pytest.raises(SnnccError, match="not a readable"):
        load_dataset(tmp_path / "g.npz")
    with open(tmp_path / "k.npz", "wb") as fh:
        np.savez(fh, inputs=np.zeros((1, 2, 24), np.uint8))
    with pytest.raises(SnnccError, match="missing key"):
        load_dataset(tmp_path / "k.npz")


def test_generator_is_seeded_and_physical():
    a, la = generate(3, seed=7)
    b, lb = generate(3, seed=7)
    c, _ = generate(3, seed=8)
    assert a.dtype == np.uint8 and a.shape == (81, 54, 12)
    assert a.tobytes() == b.tobytes() and not np.array_equal(a, c)
    assert la.tolist() == [i for i in range(27) for _ in range(3)]
    space = a[la == 0].astype(int)
    assert np.median(space) >= 245  # 255 at rest: 'Space' has no dots, only offsets and noise
    letters = a[la > 0].astype(int)
    assert letters.min() < 230  # dots load the taxels (version 2 saturates near 30-40 counts; version 1: < 200)
    # the most exposed taxels (y = 4.4: 1 and 6) respond more than the side ones (3, 4: y = -1.4)
    load = (255 - letters).mean(axis=(0, 1))
    assert load[[1, 6]].min() > load[[3, 4]].max()


def test_synth_encode_frames_cli(tmp_path, capsys):
    out = tmp_path / "set"
    code, stdout, _ = cli(["data", "synth", "--out", out, "-n", "2", "--seed", "1", "--json"], capsys)
    assert code == 0
    rec = json.loads(stdout)
    assert rec["samples"] == 54 and rec["synthetic"] is True
    names = sorted(p.name for p in out.iterdir())
    assert names == ["SYNTHETIC.json", "data_braille_letters_raw.pkl"] + sorted(
        f"data_braille_letters_th_{t}.pkl" for t in (1, 2, 5, 10))
    # the event files are exactly the encoding of the raw file
    rs = formats.load_raw(out / formats.RAW_NAME)
    es = formats.load_events(out / "data_braille_letters_th_2.pkl")
    ev = encode(rs.inverted(), 2)
    np.testing.assert_array_equal(es.events.times, ev.times)
    # encode from the directory (event file) and from the raw file agree
    code, _, _ = cli(["data", "encode", out, "-t", "2", "-b", "3", "-o", tmp_path / "a.npz"], capsys)
    assert code == 0
    code, _, _ = cli(["data", "encode", out / formats.RAW_NAME, "-t", "2", "-b", "3",
                      "-o", tmp_path / "b.npz", "--split-test", "0.5"], capsys)
    assert code == 0
    xa, ya, ma = load_dataset(tmp_path / "a.npz")
    xb, yb, mb = load_dataset(tmp_path / "b.npz")
    np.testing.assert_array_equal(xa, xb)
    assert xa.shape == (54, 450, 24) and xa.dtype == np.uint8
    np.testing.assert_array_equal(xa, bin_events(ev, 3, 450))
    assert ma["kind"] == "events" and ma["threshold"] == 2 and ma["time_bin_size_ms"] == 3
    assert ma["dt_s"] == 0.003 and ma["n_steps"] == 450 and ma["synthetic"] is True and ma["seed"] == 1
    assert ma["classes"] == list(CLASSES)
    xtr, ytr, _ = load_dataset(tmp_path / "b_train.npz")
    xte, yte, mte = load_dataset(tmp_path / "b_test.npz")
    assert len(yte) + len(ytr) == 54 and mte["split"] == "test"
    assert np.bincount(yte, minlength=27).tolist() == [1] * 27  # stratified
    code, _, err = cli(["data", "encode", out, "-t", "2", "-o", tmp_path / "c.npz", "--split-test", "0.2"], capsys)
    assert code == 2 and "--split-test" in err and not (tmp_path / "c.npz").exists()
    code, _, err = cli(["data", "encode", out / "data_braille_letters_th_5.pkl", "-t", "2", "-o", tmp_path / "d.npz"],
                       capsys)
    assert code == 2 and "--threshold" in err and not (tmp_path / "d.npz").exists()
    code, _, _ = cli(["data", "frames", out, "-o", tmp_path / "f.npz"], capsys)
    xf, yf, mf = load_dataset(tmp_path / "f.npz")
    assert code == 0 and xf.shape == (54, 54, 12) and xf.dtype == np.float32 and mf["kind"] == "frames"
    np.testing.assert_array_equal(xf, rs.inverted().astype(np.float32))


def test_analyse_cli_text_json_figures(small_set, tmp_path, capsys):
    d, raw, labels = small_set
    figs = tmp_path / "figs"
    code, stdout, _ = cli(["data", "analyse", d, "--json", "--figures", figs, "--pca-step", "53",
                           "--jobs", "1"], capsys)
    assert code == 0
    r = json.loads(stdout)
    enc = {row["threshold"]: row for row in r["encoding"]}
    assert sorted(enc) == [1, 2, 5, 10]
    assert enc[1]["mse"] == 0 and enc[1]["compression"] == 1
    assert all(enc[t]["events_binned"] <= enc[t]["events"] for t in enc)
    assert enc[10]["events"] < enc[5]["events"] < enc[2]["events"] < enc[1]["events"]
    for k in ("raw", "collapsed"):
        assert 0 <= r["svm_frames"][k]["mean_pct"] <= 100
    assert [p["frames"] for p in r["svm_pca_vs_frames"]] == [1, 54]
    assert r["svm_events"]["all_bins"]["n_features"] == 270 * 24
    assert r["synthetic"] is False  # the fixture set has no SYNTHETIC.json marker
    figs_ = {(f["name"], f["protocol"].split(":")[0]): f for f in r["paper_figures"]["figures"]}
    assert figs_[("svm_raw", "fullscale_C100")]["paper"] == 86.7
    assert figs_[("lost_th1_bin5_pct", "th 1, 5 ms bins")]["paper"] == 34.0
    assert {n for n, _ in figs_} >= {"events_th1", "isi_below_1ms_th1_pct", "svm_collapsed",
                                      "svm_events_all_bins", "svm_events_spatial"}
    assert sorted(p.name for p in figs.iterdir()) == ["events_vs_bin_size.png", "reconstruction.png",
                                                      "svm_vs_frames.png"]
    code, stdout, _ = cli(["data", "analyse", d, "--no-svm", "--no-event-svm", "--pca-step", "0"], capsys)
    assert code == 0 and "Encoding" in stdout


def test_help_texts(capsys):
    for cmd in (["data"], ["data", "synth"], ["data", "encode"], ["data", "analyse"], ["data", "frames"]):
        code, stdout, _ = cli(cmd + ["--help"], capsys)
        assert code == 0 and "Usage" in stdout


def test_release_2_layout_with_51_frames(tmp_path, capsys):
    """Release 2 (DataFrames, 51 frames = 1275 ms): events are binned over the raw file's length."""
    from dataclasses import replace

    import pandas as pd

    from snncc.data.synth import DEFAULT_PARAMS

    raw, labels = generate(1, seed=2, params=replace(DEFAULT_PARAMS, n_frames=51))
    d = tmp_path / "r2"
    formats.write_raw(d / formats.RAW_NAME, raw, labels, release=2)
    ev = encode(255 - raw.astype(np.int64), 1)
    formats.write_events(d / "data_braille_letters_th_1.pkl", ev, labels, release=2)
    assert isinstance(pd.read_pickle(d / formats.RAW_NAME), pd.DataFrame)
    code, _, _ = cli(["data", "encode", d, "-t", "1", "-b", "5", "-o", tmp_path / "e.npz"], capsys)
    x, y, meta = load_dataset(tmp_path / "e.npz")
    assert code == 0 and x.shape == (27, 255, 24) and meta["record_ms"] == 1275
    np.testing.assert_array_equal(x, bin_events(ev, 5, 255))
    code, stdout, _ = cli(["data", "synth", "-o", tmp_path / "s2", "-n", "1", "--release", "2",
                           "--thresholds", "5", "--json"], capsys)
    assert code == 0 and isinstance(pd.read_pickle(tmp_path / "s2" / "data_braille_letters_th_5.pkl"), pd.DataFrame)
