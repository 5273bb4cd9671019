"""Loader fuzzing: random, truncated, mutated and ill-structured files give SnnccError, never a crash."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from snncc.data import formats
from snncc.errors import SnnccError

LOADERS = [formats.load_raw, formats.load_events]
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

leaf = st.one_of(st.none(), st.booleans(), st.integers(-300, 300), st.floats(allow_nan=True),
                 st.text(max_size=3), st.sampled_from(["A", "Space", "Z"]))
junk = st.recursive(leaf, lambda c: st.one_of(st.lists(c, max_size=13), st.dictionaries(st.sampled_from(
    ["letter", "taxel_data", "events", "x"]), c, max_size=3)), max_leaves=40)


def _check(path):
    for load in LOADERS:
        try:
            load(path)
        except SnnccError as err:
            assert err.line()  # one line naming what is wrong
            assert "\n" not in err.line()


@SETTINGS
@given(junk)
def test_ill_structured_pickles(tmp_path_factory, obj):
    p = tmp_path_factory.mktemp("fz") / "f.pkl"
    with open(p, "wb") as fh:
        pickle.dump(obj, fh)
    _check(p)


@SETTINGS
@given(st.lists(st.sampled_from(["A", "B", "Space"]), min_size=1, max_size=3),
       st.lists(st.tuples(st.integers(0, 12), st.one_of(st.none(), st.floats(), st.text(max_size=2),
                                                         st.lists(st.floats(), max_size=3))), max_size=4))
def test_mutated_event_records(tmp_path_factory, letters, edits):
    events = [[[[0.1, 0.2], [0.3]] for _ in range(12)] for _ in letters]
    for k, val in edits:
        if k < 12:
            events[0][k][0] = val
        else:
            events[0].append(val)
    p = tmp_path_factory.mktemp("fz") / "e.pkl"
    with open(p, "wb") as fh:
        pickle.dump([{"letter": l, "events": e} for l, e in zip(letters, events)], fh)
    _check(p)


@SETTINGS
@given(st.binary(max_size=200))
def test_random_bytes(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("fz") / "r.pkl"
    p.write_bytes(data)
    _check(p)


@pytest.mark.parametrize("release", [1, 2])
def test_truncated_files(tmp_path, release):
    raw = np.full((2, 54, 12), 250, np.uint8)
    good = tmp_path / "g.pkl"
    formats.write_raw(good, raw, np.array([1, 2]), release=release)
    data = good.read_bytes()
    for cut in np.linspace(0, len(data) - 1, 25).astype(int):
        p = tmp_path / f"t{cut}.pkl"
        p.write_bytes(data[:cut])
        with pytest.raises(SnnccError):
            formats.load_raw(p)
