"""Shared fixtures: small seeded models and files in the formats users bring."""

from __future__ import annotations

import os

import pytest
import torch
from hypothesis import settings

from snncc.frontends.checkpoint import save_checkpoint
from snncc.models import SNNConfig, SpikingClassifier

from snncc_test_helpers import TH1_PARAMS

# CI (CI=true) draws hypothesis examples from a fixed seed, so a red run is reproducible and a landing is
# never decided by a new random draw; local runs keep exploring (what they find is pinned as @example)
settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI") == "true":
    settings.load_profile("ci")


@pytest.fixture(autouse=True)
def _one_torch_thread():
    """Tests run tiny tensors: extra torch threads only contend for the 2 cores."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope="session")
def shared_nir():
    """The real NIR graphs other frameworks wrote (tests/data/nir, BSD-3-Clause: see its README)."""
    from pathlib import Path

    return Path(__file__).resolve().parent / "data" / "nir"


def _rsnn_checkpoint(path, **meta):
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_hidden=32, n_outputs=28))
    model.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.2)
    save_checkpoint(model, path, {"dt": 0.005, "note": "test model", **meta})
    return path


@pytest.fixture
def small_rsnn_checkpoint(tmp_path):
    return _rsnn_checkpoint(tmp_path / "rsnn.pt")


@pytest.fixture
def short_rsnn_checkpoint(tmp_path):
    """small_rsnn_checkpoint's model (the same seeded weights) stating a 0.1 s recording: 20 steps of 5 ms,
    so a Jetson artefact unrolls 20 steps instead of the model's default 270 (an export ~10x cheaper)."""
    return _rsnn_checkpoint(tmp_path / "rsnn.pt", recording_length_s=0.1)


@pytest.fixture
def th1_params(tmp_path):
    p = tmp_path / "parameters_th1.txt"
    p.write_text(TH1_PARAMS)
    return p


@pytest.fixture
def authors_weights(tmp_path):
    """A weight list shaped like the authors' th1 RSNN but smaller hidden layer."""
    g = torch.Generator().manual_seed(1)
    ws = [torch.randn(48, 40, generator=g) * 0.4, torch.randn(40, 28, generator=g) * 0.4,
          torch.randn(40, 40, generator=g) * 0.05]
    path = tmp_path / "weights_th1.pt"
    torch.save(ws, path)
    return path
