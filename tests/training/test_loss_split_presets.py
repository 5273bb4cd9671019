"""The authors' loss, the stratified split and the paper's presets."""

import math

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.training.loss import lstm_loss, snn_loss, spike_count_prediction
from snncc.training.presets import PRESETS, paper_preset, parse_overrides, with_overrides
from snncc.data.split import stratified_split


def test_snn_loss_matches_hand_computation():
    out = torch.zeros(2, 3, 4)
    out[0, :, 1] = 1          # sample 0: class 1 fires 3 times
    out[1, 0, 2] = 1          # sample 1: class 2 fires once
    hid = torch.zeros(2, 3, 5)
    hid[0, 0, 0] = hid[0, 1, 0] = hid[1, 2, 4] = 1
    labels = torch.tensor([1, 0])
    parts = snn_loss(out, hid, labels, reg_spikes=0.5, reg_neurons=0.25)
    c0 = np.array([0, 3, 0, 0.0])
    c1 = np.array([0, 0, 1, 0.0])
    nll = (-(c0[1] - np.log(np.exp(c0).sum())) - (c1[0] - np.log(np.exp(c1).sum()))) / 2
    l1 = 0.5 * 3 / (2 * 5)                      # 3 hidden spikes over batch x neurons
    l2 = 0.25 * (2 ** 2 + 1 ** 2) / 5           # per-neuron totals 2 and 1, squared, mean over neurons
    assert parts.nll == pytest.approx(nll)
    assert parts.reg_spikes == pytest.approx(l1)
    assert parts.reg_neurons == pytest.approx(l2)
    assert float(parts.total) == pytest.approx(nll + l1 + l2, rel=1e-6)


def test_lstm_loss_is_cross_entropy():
    scores = torch.tensor([[2.0, 0.0], [0.0, 1.0]])
    parts = lstm_loss(scores, torch.tensor([0, 0]))
    expected = (-(2 - math.log(math.exp(2) + 1)) - (0 - math.log(1 + math.e))) / 2
    assert float(parts.total) == pytest.approx(expected)


def test_prediction_ties_go_to_the_lowest_index():
    out = torch.zeros(1, 4, 5)
    out[0, :2, 3] = 1
    out[0, 2:, 1] = 1          # classes 1 and 3 both fire twice
    assert spike_count_prediction(out).tolist() == [1]
    assert spike_count_prediction(torch.zeros(1, 4, 5)).tolist() == [0]


def test_split_is_stratified_seeded_and_disjoint():
    labels = np.repeat(np.arange(27), 200)
    a = stratified_split(labels, seed=3)
    b = stratified_split(labels, seed=3)
    c = stratified_split(labels, seed=4)
    assert np.array_equal(a.train, b.train) and np.array_equal(a.test, b.test)
    assert not np.array_equal(a.test, c.test)
    assert a.train.size == 4320 and a.test.size == 1080 and a.val.size == 0
    assert np.intersect1d(a.train, a.test).size == 0
    assert np.all(np.bincount(labels[a.test]) == 40)


def test_validation_split_comes_out_of_training():
    labels = np.repeat(np.arange(27), 200)
    s = stratified_split(labels, seed=0, val_fraction=0.1)
    assert s.test.size == 1080 and s.val.size == 540 and s.train.size == 3780
    assert np.all(np.bincount(labels[s.val]) == 20)
    everything = np.concatenate([s.train, s.val, s.test])
    assert np.array_equal(np.sort(everything), np.arange(labels.size))


@pytest.mark.parametrize("bad", [-0.1, 0.8, 1.0])
def test_bad_validation_fraction_is_refused(bad):
    with pytest.raises(SnnccError, match="validation fraction"):
        stratified_split(np.repeat(np.arange(3), 10), val_fraction=bad)


def test_presets_are_the_papers_table():
    th1 = paper_preset(1)
    assert (th1.scale, th1.time_bin_size, th1.nb_input_copies, th1.tau_mem, th1.tau_ratio) == (5, 5, 2, 0.06, 10)
    assert (th1.fwd_weight_scale, th1.weight_scale_factor, th1.reg_spikes, th1.reg_neurons) == (1, 0.01, 0.004, 1e-6)
    assert th1.tau_syn == pytest.approx(0.006) and th1.dt == pytest.approx(0.005)
    rows = {th: (p.scale, p.time_bin_size, p.nb_input_copies, p.tau_mem, p.fwd_weight_scale,
                 p.weight_scale_factor, p.reg_spikes, p.reg_neurons) for th, p in PRESETS.items()}
    assert rows[2] == (15, 3, 8, 0.05, 1, 0.02, 0.0015, 0)
    assert rows[5] == (10, 3, 4, 0.07, 1.5, 0.035, 0.001, 0)
    assert rows[10] == (10, 5, 2, 0.07, 4, 0.015, 0.0015, 0)
    with pytest.raises(SnnccError, match="no paper preset"):
        paper_preset(3)


def test_overrides_are_validated():
    p = with_overrides(paper_preset(1), parse_overrides(["tau_mem=0.05", "nb_input_copies=4"]))
    assert p.tau_mem == 0.05 and p.nb_input_copies == 4 and p.scale == 5
    with pytest.raises(SnnccError, match="unknown hyper-parameter"):
        with_overrides(paper_preset(1), {"tau": "1"})
    with pytest.raises(SnnccError, match="must be positive"):
        with_overrides(paper_preset(1), {"tau_mem": "-1"})
    with pytest.raises(SnnccError, match="KEY=VALUE"):
        parse_overrides(["tau_mem"])


def test_subset_is_seeded_and_keeps_the_class_proportions():
    from snncc.training.training_set import subset_indices

    labels = np.repeat(np.arange(27), 6)
    a = subset_indices(labels, 150, seed=0)
    assert a.size == 150 and np.unique(a).size == 150
    assert set(np.bincount(labels[a])) <= {5, 6}
    assert np.array_equal(a, subset_indices(labels, 150, seed=0))
    assert not np.array_equal(a, subset_indices(labels, 150, seed=1))
    assert subset_indices(labels, None, 0).size == 162 and subset_indices(labels, 500, 0).size == 162
    with pytest.raises(SnnccError, match="^subset: a subset needs"):
        subset_indices(labels, 20, 0)
