"""Seeded training: reproducible to the bit and better than chance on an easy toy set."""

import pytest
import torch

from snncc.data.split import stratified_split
from snncc.training.trainer import TrainSettings, accuracy, build_model, train_model

from .conftest import toy_events


def _toy_sets(kind):
    x, y = toy_events()
    split = stratified_split(y, seed=0)
    xt = torch.from_numpy(x)
    if kind == "lstm":
        xt = xt[..., :12].float() + xt[..., 12:].float()   # a 12-channel analog view of the same data
    yt = torch.from_numpy(y)
    return (xt[split.train], yt[split.train]), (xt[split.test], yt[split.test])


def _fit(kind, seed=0, epochs=8):
    train, test = _toy_sets(kind)
    torch.manual_seed(seed)
    if kind in ("rsnn", "ffsnn"):
        model = build_model(kind, n_hidden=32, n_outputs=28, input_copies=1)
        model.reset_parameters(1.0, 0.2)
        settings = TrainSettings(epochs=epochs, batch_size=16, seed=seed, lr=0.01, reg_spikes=0.004, reg_neurons=1e-6)
    else:
        model = build_model(kind, n_inputs=12, n_hidden=16, n_outputs=27)
        settings = TrainSettings(epochs=epochs, batch_size=16, seed=seed, lr=0.01)
    history = train_model(model, train, test, settings)
    return model, history, test


@pytest.mark.parametrize("kind", ["rsnn", "lstm"])
def test_seeded_training_is_reproducible(kind):
    a, ha, _ = _fit(kind, epochs=2)
    b, hb, _ = _fit(kind, epochs=2)
    for (name, pa), (_, pb) in zip(a.state_dict().items(), b.state_dict().items()):
        assert torch.equal(pa, pb), name
    assert [e.loss for e in ha.epochs] == [e.loss for e in hb.epochs]
    c, _, _ = _fit(kind, seed=1, epochs=2)
    assert not torch.equal(next(iter(a.parameters())), next(iter(c.parameters())))


@pytest.mark.parametrize("kind", ["rsnn", "ffsnn", "lstm"])
def test_training_beats_chance_on_a_separable_toy_set(kind):
    model, history, test = _fit(kind, epochs=5 if kind != "lstm" else 25)
    acc = accuracy(model, *test)
    assert acc >= 0.8, f"{kind}: {acc} (chance 0.33)"
    # the model holds the selected (best test) epoch's weights, as recorded
    assert acc == pytest.approx(history.best_test_accuracy)
    assert history.selected_on == "test" and "TEST" in history.note


def test_validation_split_selects_on_validation():
    x, y = toy_events()
    split = stratified_split(y, seed=0, val_fraction=0.2)
    xt, yt = torch.from_numpy(x), torch.from_numpy(y)
    torch.manual_seed(0)
    model = build_model("ffsnn", n_hidden=16, n_outputs=28, input_copies=1)
    history = train_model(model, (xt[split.train], yt[split.train]), (xt[split.test], yt[split.test]),
                          TrainSettings(epochs=3, batch_size=16), val=(xt[split.val], yt[split.val]))
    assert history.selected_on == "val"
    best = max(history.epochs, key=lambda e: (e.val_accuracy, -e.epoch))
    assert history.best_epoch == best.epoch
    assert accuracy(model, xt[split.val], yt[split.val]) == pytest.approx(best.val_accuracy)


def test_fine_tuning_keeps_the_starting_weights_when_no_epoch_beats_them():
    train, test = _toy_sets("ffsnn")
    torch.manual_seed(0)
    model = build_model("ffsnn", n_hidden=16, n_outputs=28, input_copies=1)
    train_model(model, train, test, TrainSettings(epochs=4, batch_size=16, lr=0.01))
    start = {k: v.clone() for k, v in model.state_dict().items()}
    start_acc = accuracy(model, *test)
    assert start_acc == 1.0
    # a learning rate this large wrecks the model in one epoch: the starting weights must win
    history = train_model(model, train, test, TrainSettings(epochs=1, batch_size=8, lr=10.0), keep_start=True)
    assert history.epochs[0].test_accuracy < start_acc
    assert history.best_epoch == 0 and history.best_test_accuracy == start_acc
    assert all(torch.equal(start[k], v) for k, v in model.state_dict().items())


def test_device_option_resolves_and_refuses_bad_names():
    import torch

    from snncc.errors import SnnccError
    from snncc.training.device import resolve_device

    assert resolve_device("cpu") == torch.device("cpu")
    assert resolve_device("auto").type == ("cuda" if torch.cuda.is_available() else "cpu")
    for bad in ("gpu", "cuda:x", "tpu:0"):
        with pytest.raises(SnnccError, match="not a device"):
            resolve_device(bad)
    if not torch.cuda.is_available():
        with pytest.raises(SnnccError, match="no CUDA device"):
            resolve_device("cuda:0")


def test_a_training_that_falls_back_after_its_best_epoch_is_named():
    from snncc.training.trainer import EpochRecord, History

    def rec(epoch, test, spikes):
        return EpochRecord(epoch, 1.0, 1.0, test, test, None, spikes, 1.0)

    h = History("test", "n", epochs=[rec(1, 0.5, 3000.0), rec(2, 0.83, 2700.0), rec(3, 0.25, 8300.0)], best_epoch=2)
    note = h.collapse_note()
    assert note == ("training fell back after epoch 2: test accuracy 83.0 % there, 25.0 % at the last epoch (3); "
                    "hidden spikes per sample 2,700 -> 8,300; the checkpoint holds epoch 2")
    assert History("test", "n", epochs=h.epochs[:2], best_epoch=2).collapse_note() is None      # best is last
    mild = History("test", "n", epochs=[rec(1, 0.83, None), rec(2, 0.70, None)], best_epoch=1)
    assert mild.collapse_note() is None                                                          # 13 points: noise
    lstm = History("test", "n", epochs=[rec(1, 0.9, None), rec(2, 0.1, None)], best_epoch=1)
    assert lstm.collapse_note().endswith("(2); the checkpoint holds epoch 1")                    # no spike counts
