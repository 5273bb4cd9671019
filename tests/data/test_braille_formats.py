"""Published-format loaders and writers: both Zenodo releases, exact round trips, clear errors."""

from __future__ import annotations

import pickle

import numpy as np
import pandas as pd
import pytest

from snncc_test_helpers import without_progress
from hypothesis import given, settings
from hypothesis import strategies as st

from snncc.data import formats
from snncc.data.letters import CLASSES, label_of
from snncc.data.sigma_delta import encode
from snncc.errors import SnnccError

from .conftest import cli


def _published_raw(n=5, t=54, seed=0):
    rng = np.random.default_rng(seed)
    letters = [CLASSES[i % 27] for i in range(n)]
    data = [255 - rng.integers(0, 40, size=(t, 12)) for _ in range(n)]
    return letters, data


def test_labels():
    assert label_of("Space") == 0 and label_of("A") == 1 and label_of("Z") == 26
    assert len(CLASSES) == 27
    with pytest.raises(SnnccError, match="unknown letter"):
        label_of("a")


def test_reads_release_1_raw_as_published(tmp_path):
    """Release 1: a plain pickled list of dicts (here with list-of-lists taxel_data and a timestamp)."""
    letters, data = _published_raw()
    recs = [{"letter": l, "taxel_data": d.tolist(), "timestamp": list(np.arange(54) / 40)}
            for l, d in zip(letters, data)]
    p = tmp_path / "data_braille_letters_raw.pkl"
    with open(p, "wb") as fh:
        pickle.dump(recs, fh)
    rs = formats.load_raw(p)
    assert rs.release == 1
    assert rs.labels.tolist() == [label_of(l) for l in letters]
    np.testing.assert_array_equal(rs.raw, np.stack(data))
    np.testing.assert_array_equal(rs.inverted(), 255 - np.stack(data))


def test_reads_release_2_dataframes_as_published(tmp_path):
    """Release 2: pandas DataFrames (51 frames, numpy taxel_data, extra columns ignored)."""
    letters, data = _published_raw(t=51)
    df = pd.DataFrame({"letter": letters, "timestamp": [np.arange(51) / 40] * len(letters),
                       "taxel_data": data})
    p = tmp_path / "raw.pkl"
    df.to_pickle(p)
    rs = formats.load_raw(p)
    assert rs.release == 2 and rs.raw.shape == (5, 51, 12)
    np.testing.assert_array_equal(rs.raw, np.stack(data))
    # events, release 2: a DataFrame with 'events' = 12 x [ON list, OFF list]
    ev_lists = [[[[0.0125, 0.5], [0.75]] if k == 3 else [[], []] for k in range(12)] for _ in letters]
    pe = tmp_path / "data_braille_letters_th_1.pkl"
    pd.DataFrame({"letter": letters, "events": ev_lists}).to_pickle(pe)
    es = formats.load_events(pe)
    assert es.release == 2 and len(es.events) == 3 * len(letters)
    assert es.events.taxel.tolist()[:3] == [3, 3, 3]
    assert es.events.polarity.tolist()[:3] == [0, 0, 1]
    assert formats.sniff(pe) == "events" and formats.sniff(p) == "raw"


def test_reads_release_1_events_as_published(tmp_path):
    letters, data = _published_raw()
    x = 255 - np.stack(data)
    ev = encode(x, 2)
    lists = formats.events_to_lists(ev)
    p = tmp_path / "data_braille_letters_th_2.pkl"
    with open(p, "wb") as fh:
        pickle.dump([{"letter": l, "events": e} for l, e in zip(letters, lists)], fh)
    es = formats.load_events(p)
    assert es.release == 1
    for a in ("sample", "taxel", "polarity", "times"):
        np.testing.assert_array_equal(getattr(es.events, a), getattr(ev, a))
    # the authors' loader idiom: `if sample[taxel][event_type]:` needs lists, not arrays
    assert all(isinstance(lst, list) for s in lists for pair in s for lst in pair)


@pytest.mark.parametrize("release", [1, 2])
def test_round_trip_exact_generated(tmp_path, release, small_set):
    _, raw, labels = small_set
    p = tmp_path / "raw.pkl"
    formats.write_raw(p, raw, labels, release=release)
    rs = formats.load_raw(p)
    assert rs.release == release
    np.testing.assert_array_equal(rs.raw, raw)
    np.testing.assert_array_equal(rs.labels, labels)
    ev = encode(255 - raw.astype(np.int64), 1)
    pe = tmp_path / "ev.pkl"
    formats.write_events(pe, ev, labels, release=release)
    back = formats.load_events(pe)
    assert back.events.n_samples == ev.n_samples
    for a in ("sample", "taxel", "polarity", "times"):
        np.testing.assert_array_equal(getattr(back.events, a), getattr(ev, a))
    assert back.events.times.tobytes() == ev.times.tobytes()  # bit-exact float64


time_lists = st.lists(st.floats(0, 1.35, allow_nan=False, allow_subnormal=False), max_size=6).map(sorted)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(CLASSES), st.lists(st.tuples(time_lists, time_lists),
                                                            min_size=12, max_size=12)),
                min_size=1, max_size=4),
       st.sampled_from([1, 2]))
def test_round_trip_exact_any_events(tmp_path_factory, samples, release):
    d = tmp_path_factory.mktemp("rt")
    lists = [[[list(on), list(off)] for on, off in taxels] for _, taxels in samples]
    letters = [l for l, _ in samples]
    p = d / "in.pkl"
    with open(p, "wb") as fh:
        pickle.dump([{"letter": l, "events": e} for l, e in zip(letters, lists)], fh)
    es = formats.load_events(p)
    assert formats.events_to_lists(es.events) == lists
    q = d / "out.pkl"
    formats.write_events(q, es.events, es.labels, release=release)
    again = formats.load_events(q)
    assert formats.events_to_lists(again.events) == lists
    assert [CLASSES[i] for i in again.labels] == letters


# ----------------------------------------------------------------------------- bad input


def _write(p, obj):
    with open(p, "wb") as fh:
        pickle.dump(obj, fh)
    return p


@pytest.mark.parametrize("obj, field, rule", [
    ([{"letter": "A"}], "sample 0.taxel_data", "missing key"),
    ([{"letter": "A", "taxel_data": np.zeros((54, 11))}], "sample 0.taxel_data", "expected 12 taxels, got 11"),
    ([{"letter": "AA", "taxel_data": np.zeros((54, 12))}], "sample 0.letter", "unknown letter"),
    ([{"letter": "A", "taxel_data": np.full((54, 12), 300)}], "sample 0.taxel_data", "0..255"),
    ([{"letter": "A", "taxel_data": np.zeros((54, 12))}, {"letter": "B", "taxel_data": np.zeros((50, 12))}],
     "sample 1.taxel_data", "all must match"),
    ({"foo": 1}, "letter", "missing column"),
    (42, None, "expected a list of dicts or a pandas DataFrame"),
])
def test_bad_raw_files_through_the_cli(tmp_path, capsys, obj, field, rule):
    p = _write(tmp_path / "data_braille_letters_raw.pkl", obj)
    out = tmp_path / "o.npz"
    code, _, err = cli(["data", "encode", p, "-t", "1", "-o", out], capsys)
    assert code == 2
    line = without_progress(err).strip()
    assert line.count("\n") == 0 and line.startswith(f"snncc: error: {p}")
    assert "Traceback" not in err
    if field:
        assert f": {field}: " in line
    assert rule in line
    assert not out.exists() and not list(tmp_path.glob(".o.npz*"))


def test_missing_dataframe_column(tmp_path, capsys):
    p = tmp_path / "raw.pkl"
    pd.DataFrame({"letter": ["A"], "data": [np.zeros((54, 12))]}).to_pickle(p)
    code, _, err = cli(["data", "frames", p, "-o", tmp_path / "f.npz"], capsys)
    assert code == 2 and ": taxel_data: missing column" in err


@pytest.mark.parametrize("events, field, rule", [
    ([[[], []]] * 11, "sample 0.events", "expected 12 taxels, got 11"),
    ([[[], []]] * 11 + [[[0.1]]], "sample 0.events[11]", "expected [ON_times, OFF_times]"),
    ([[[], []]] * 11 + [[[0.2, 0.1], []]], "sample 0.events[11][0] (ON)", "not chronological"),
    ([[[], []]] * 11 + [[[float("nan")], []]], "sample 0.events[11][0] (ON)", "NaN"),
    ([[[], []]] * 11 + [[[], ["x"]]], "sample 0.events[11][1] (OFF)", "list of numbers"),
])
def test_bad_event_files_through_the_cli(tmp_path, capsys, events, field, rule):
    p = _write(tmp_path / "data_braille_letters_th_1.pkl", [{"letter": "B", "events": events}])
    code, _, err = cli(["data", "encode", p, "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and "Traceback" not in err
    assert f"{p}: {field}: " in err and rule in err


def test_not_a_pickle(tmp_path, capsys):
    p = tmp_path / "data_braille_letters_raw.pkl"
    p.write_bytes(b"\x00garbage" * 20)
    code, _, err = cli(["data", "analyse", tmp_path, "--no-svm", "--no-event-svm", "--pca-step", "0"], capsys)
    assert code == 2 and "not a readable pickle" in err and "Traceback" not in err
    code, _, err = cli(["data", "encode", tmp_path / "nope.pkl", "-t", "1", "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and "no such file" in err


def test_event_beyond_record_names_the_sample(tmp_path, capsys):
    ev = [[[], []]] * 11 + [[[1.5], []]]
    p = _write(tmp_path / "data_braille_letters_th_1.pkl", [{"letter": "B", "events": ev}])
    code, _, err = cli(["data", "encode", p, "-o", tmp_path / "o.npz"], capsys)
    assert code == 2 and "sample 0.events" in err and "outside" in err
    code, _, _ = cli(["data", "encode", p, "-o", tmp_path / "o.npz", "--record-ms", "1600"], capsys)
    assert code == 0
