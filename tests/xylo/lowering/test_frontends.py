"""Every frontend's models that Xylo can hold lower; what it cannot hold is refused in one line."""

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.frontends import LoadOptions, graph_from_object, load_model
from snncc.frontends.checkpoint import save_checkpoint
from snncc.ir.simulate import simulate
from snncc.models import SNNConfig, SpikingClassifier
from snncc.targets.kit.agreement import argmax_agreement
from xylo_models import lower_with

from xylo_models import run_xylosim

QUICK = {"calibration_samples": 16, "time_steps": 64, "density": 0.1}
NIR = __import__("pathlib").Path(__file__).resolve().parents[2] / "data" / "nir"


def small_rsnn(order):
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_inputs=12, input_copies=1, n_hidden=24, n_outputs=7, order=order))
    model.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.2)
    return model


def test_the_papers_rsnn_in_its_training_order_is_refused(tmp_path):
    path = tmp_path / "rsnn.pt"
    save_checkpoint(small_rsnn("spytorch"), path, {"dt": 0.005})
    g = load_model(path)
    with pytest.raises(SnnccError, match="cannot reset to zero"):
        lower_with(g, QUICK)
    with pytest.raises(SnnccError, match="a recurrent projection with IR delay 3 steps"):
        lower_with(g, dict(QUICK, allow_reset_change=True))
    g.set_delay("hidden", "w_rec", 1)
    with pytest.raises(SnnccError, match="refractory: 2 steps"):
        lower_with(g, dict(QUICK, allow_reset_change=True))


def test_an_snncc_checkpoint_in_hardware_order_lowers(tmp_path):
    path = tmp_path / "rsnn.pt"
    save_checkpoint(small_rsnn("loihi"), path, {"dt": 0.005})
    g = load_model(path)
    low = lower_with(g, dict(QUICK, allow_reset_change=True, rule="single"))
    # IR delays 1 (input), 1 (recurrent), 1 (readout); chip 0, 1, 1: the input is fed one step late, and the
    # output then needs no lag
    assert (low.timing.input_pad, low.timing.output_lag) == (1, 0)
    assert low.spec["weights_in"].shape == (12, 24, 2) and len(low.changes) == 2


def test_a_torch_module_lowers():
    g = graph_from_object(small_rsnn("loihi"))
    low = lower_with(g, dict(QUICK, allow_reset_change=True, rule="direct"))
    assert low.spec["weights_out"].shape == (24, 7)


def test_the_nir_braille_graph_lowers_and_xylosim_follows_the_float_graph():
    g = load_model(NIR / "braille_noDelay_noBias_subtract.nir", LoadOptions(dt=1e-4, reset="subtract"))
    low = lower_with(g, dict(QUICK, rule="single-identified", calibration_samples=32, time_steps=128, density=0.08))
    assert low.spec["weights_in"].shape == (12, 40, 2) and low.spec["weights_out"].shape == (40, 7)
    assert (low.timing.input_pad, low.timing.output_lag) == (0, 1)     # hidden -> output: IR 0, chip 1
    x = (np.random.default_rng(7).random((80, 128, 12)) < 0.08).astype(np.uint8)
    out = run_xylosim(low.spec, low.chip_input(x), record=True)
    counts = low.read_output(out.output_spikes, 128).sum(axis=1)
    ref = np.asarray(simulate(g, x, record="spikes").spikes["lif2"]).sum(axis=1)
    agr = argmax_agreement(ref, counts)
    # Rockpool's own flow keeps about 0.52 on such inputs; the bench measures 1,000 samples
    assert agr.decided > 40 and agr.share > 0.6, agr.text()
    assert out.spikes.max() == 1
