"""Sigma-delta encoding and time binning: properties (hypothesis) and the spec's exact pipeline."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from snncc.data.binning import bin_events, bin_index, n_bins_for, record_ms, tile_copies
from snncc.data.sigma_delta import Events, encode, isi_share_below, reconstruct


def reference_trace(x: list[int], th: float) -> list[tuple[int, float]]:
    """The spec's rule, literally, in plain Python: [(polarity, t)] for one taxel."""
    out = []
    r = x[0]
    for n in range(len(x) - 1):
        v = x[n + 1]
        while r + th <= v:
            L = r + th
            out.append((0, (n + (L - x[n]) / (x[n + 1] - x[n])) * (1 / 40)))
            r += th
        while r - th >= v:
            L = r - th
            out.append((1, (n + (L - x[n]) / (x[n + 1] - x[n])) * (1 / 40)))
            r -= th
    return out


frames_st = st.integers(1, 3).flatmap(
    lambda n: st.integers(2, 30).flatmap(
        lambda t: st.integers(1, 4).flatmap(
            lambda c: arrays(np.int64, (n, t, c), elements=st.integers(0, 255)))))
thresholds = st.sampled_from([1, 2, 3, 5, 10])


@settings(max_examples=60, deadline=None)
@given(frames_st)
def test_th1_reconstructs_exactly_and_counts_sum_abs_dx(x):
    ev = encode(x, 1)
    assert len(ev) == int(np.abs(np.diff(x, axis=1)).sum())
    np.testing.assert_array_equal(ev.counts(), np.abs(np.diff(x, axis=1)).sum(axis=1))
    rec = reconstruct(ev, x[:, 0, :], x.shape[1], 1)
    np.testing.assert_array_equal(rec, x)


@settings(max_examples=60, deadline=None)
@given(frames_st, thresholds)
def test_matches_the_spec_loop_bit_for_bit(x, th):
    ev = encode(x, th)
    n, t, c = x.shape
    for i in range(n):
        for k in range(c):
            ref = reference_trace([int(v) for v in x[i, :, k]], th)
            m = (ev.sample == i) & (ev.taxel == k)
            got = list(zip(ev.polarity[m].tolist(), ev.times[m].tolist()))
            assert got == ref  # same order, same float64 bits


@settings(max_examples=60, deadline=None)
@given(frames_st, thresholds)
def test_reconstruction_stays_within_one_threshold(x, th):
    ev = encode(x, th)
    rec = reconstruct(ev, x[:, 0, :], x.shape[1], th)
    assert np.all(np.abs(rec - x) < th)
    # chronological per (sample, taxel), inside the recording
    key = ev.sample * 100 + ev.taxel
    same = key[1:] == key[:-1]
    assert np.all(np.diff(ev.times)[same] >= 0)
    assert np.all(ev.times > 0) and np.all(ev.times <= (x.shape[1] - 1) / 40 + 1e-12)


def test_jump_spreads_events_over_the_frame():
    x = np.array([[[0], [4], [4], [0]]])
    ev = encode(x, 1)
    assert ev.polarity.tolist() == [0, 0, 0, 0, 1, 1, 1, 1]
    assert ev.times.tolist() == [(0 + k / 4) * (1 / 40) for k in (1, 2, 3, 4)] + \
        [(2 + k / 4) * (1 / 40) for k in (1, 2, 3, 4)]


def test_rejects_bad_threshold_and_nan():
    from snncc.errors import SnnccError

    with pytest.raises(SnnccError, match="threshold"):
        encode(np.zeros((1, 3, 12)), 0)
    with pytest.raises(SnnccError, match="NaN"):
        encode(np.full((1, 3, 12), np.nan), 1)


# ----------------------------------------------------------------------------- binning


def test_bins_follow_the_spec_pipeline_and_round_half_to_even():
    # a 2-count jump at th 1 puts events at 12.5 ms and 25 ms: 12.5/5 = 2.5 -> bin 2 (half to even)
    x = np.array([[[0], [2], [2], [2]]])
    ev = encode(x, 1)
    assert ev.times.tolist() == [0.5 * (1 / 40), 1.0 * (1 / 40)]
    assert bin_index(ev.times, 5).tolist() == [2, 5]
    assert bin_index(np.array([0.0075]), 5).tolist() == [2]  # 1.5 -> 2
    t = np.array([0.0125, 0.0375, 0.0625])
    np.testing.assert_array_equal(bin_index(t, 5), np.round(1000 * t / 5).astype(np.int64))
    assert n_bins_for(record_ms(54), 5) == 270
    assert n_bins_for(record_ms(54), 3) == 450
    assert n_bins_for(record_ms(51), 5) == 255
    assert n_bins_for(record_ms(54), 4) == math.ceil(1350 / 4)


@settings(max_examples=40, deadline=None)
@given(frames_st, thresholds, st.sampled_from([1, 2, 3, 5, 10]))
def test_binning_never_creates_events(x, th, b):
    ev = encode(x, th)
    n_bins = n_bins_for(record_ms(x.shape[1]), b)
    binned = bin_events(ev, b, n_bins)
    assert binned.dtype == np.uint8 and set(np.unique(binned)) <= {0, 1}
    assert binned.shape == (x.shape[0], n_bins, 2 * x.shape[2])
    assert int(binned.sum()) <= len(ev)
    # every 1 has an event behind it, every event lands on a 1
    idx = bin_index(ev.times, b)
    ch = 2 * ev.taxel + ev.polarity
    made = np.zeros_like(binned)
    made[ev.sample, idx, ch] = 1
    np.testing.assert_array_equal(made, binned)


def test_channels_are_interleaved_per_taxel():
    ev = Events(np.array([0, 0]), np.array([3, 3]), np.array([0, 1], np.int8), np.array([0.01, 0.02]), 1)
    binned = bin_events(ev, 5, 270)
    assert binned[0, 2, 6] == 1 and binned[0, 4, 7] == 1 and binned.sum() == 2


def test_events_outside_the_record_are_an_error():
    from snncc.errors import SnnccError

    ev = Events(np.array([0]), np.array([0]), np.array([0], np.int8), np.array([2.0]), 1)
    with pytest.raises(SnnccError, match="outside"):
        bin_events(ev, 5, 270)


def test_tile_copies_numpy_and_torch():
    x = np.arange(2 * 3 * 24).reshape(2, 3, 24)
    y = tile_copies(x, 3)
    assert y.shape == (2, 3, 72)
    np.testing.assert_array_equal(y[..., 24:48], x)
    np.testing.assert_array_equal(y[..., 48:], x)
    tt = torch.tensor(x)
    np.testing.assert_array_equal(tile_copies(tt, 3).numpy(), y)
    np.testing.assert_array_equal(tt.tile((3,)).numpy(), y)  # the authors' call


def test_isi_share():
    x = np.array([[[0], [60]]])  # 60 events in 25 ms: ISIs of 25/60 ms < 1 ms
    share, n = isi_share_below(encode(x, 1))
    assert n == 59 and share == 1.0
    share2, _ = isi_share_below(encode(np.array([[[0], [10], [20]]]), 1))
    assert share2 == 0.0
