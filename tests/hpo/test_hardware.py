"""A trial's Loihi figures: compiled, estimated, and the emulated accuracy beside the float model's."""

from __future__ import annotations

import numpy as np
import torch

from snncc.hpo.search_events import load_source
from snncc.hpo.hardware import hardware_figures
from snncc.targets.loihi.estimate.search_figures import fit_inputs
from snncc.training.pipeline import TrainRequest, assigned, train
from snncc.training.trainer import accuracy


def test_hardware_figures_of_a_trained_trial(braille_dir, tmp_path):
    source = load_source(braille_dir, 1)
    assert source.synthetic and source.record_ms == 1350.0
    data = source.binned(10)
    assert tuple(data.inputs.shape) == (189, 135, 24) and data.meta["time_bin_size_ms"] == 10.0
    assert source.binned(10) is data                       # cached
    ckpt = tmp_path / "t.pt"
    seen = []
    req = TrainRequest(kind="rsnn", data=str(braille_dir), output=str(ckpt), threshold=1, epochs=1, seed=0,
                       val_fraction=0.2, batch_size=64, n_hidden=8, device="cpu",
                       overrides={"time_bin_size": 10, "nb_input_copies": 2, "fwd_weight_scale": 3.0})
    train(req, data=data, on_epoch=seen.append)
    assert [r.epoch for r in seen] == [1] and seen[0].val_accuracy is not None      # the per-epoch hook
    meta = torch.load(ckpt, weights_only=True)["metadata"]
    val = assigned(meta["split_assignment"], "val")
    x, y = data.inputs[val].numpy(), data.labels[val].numpy()
    hw = hardware_figures(ckpt, x, y, energy_samples=3, emulate_samples=6)
    assert hw.cores >= 1 and hw.chips == 1 and hw.t_sample >= 135 and hw.estimated_on == 3
    assert hw.synaptic_ops_per_sample > 0 and hw.energy_uj_per_sample > 0 and hw.delay_ms_per_sample > 0
    assert "ESTIMATE" in hw.label and hw.emulated_on == 6 and 0 <= hw.emulated_accuracy <= 1
    # the IR reference run inside the check agrees with the torch model on the same samples
    from snncc.frontends.checkpoint import module_from_checkpoint

    model = module_from_checkpoint(torch.load(ckpt, weights_only=True))
    assert hw.float_accuracy_same_samples == accuracy(model, data.inputs[val][:6], data.labels[val][:6])


def test_fit_inputs_tiles_copies_and_pads_to_t_sample():
    class Net:
        input_width, t_sample = 48, 7

    x = np.arange(2 * 5 * 24).reshape(2, 5, 24) % 2
    out = fit_inputs(x, Net)
    assert out.shape == (2, 7, 48) and (out[:, :5, 24:] == x).all() and not out[:, 5:].any()
