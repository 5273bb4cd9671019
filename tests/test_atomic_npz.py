"""write_npz_atomic: numpy.load reads what it writes; a failure leaves no file."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.atomic import write_npz_atomic


def test_npz_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    arrays = {"output_spikes": (rng.random((3, 50, 4)) < 0.1).astype(np.uint8), "counts": np.arange(12).reshape(3, 4),
              "overflow_q_wrap": np.int64(5)}
    dest = tmp_path / "out.npz"
    write_npz_atomic(dest, arrays)
    with np.load(dest) as z:
        assert sorted(z.files) == sorted(arrays)
        for k, v in arrays.items():
            assert z[k].dtype == np.asarray(v).dtype and np.array_equal(z[k], v)


def test_npz_failure_leaves_nothing(tmp_path):
    dest = tmp_path / "out.npz"
    with pytest.raises(ValueError):   # object arrays need pickle, which is refused
        write_npz_atomic(dest, {"ok": np.zeros(3), "bad": np.array([{"a": 1}], dtype=object)})
    assert list(tmp_path.iterdir()) == []
