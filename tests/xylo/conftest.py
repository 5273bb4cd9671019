"""Shared fixtures of the Xylo tests: expensive things made once per session (a compiled artefact, XyloSim builds)."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))

QUICK = ["--calibration-samples", "12", "--time-steps", "48"]


@pytest.fixture(scope="session")
def compiled(tmp_path_factory):
    """(model, artefact, inputs): a small chain (``xylo_models.chain``, seed 0) compiled once with ``--rule single``
    (two synaptic currents) and ``QUICK``, and (5, 40, 6) seeded spikes. Read-only: tests copy it to change it."""
    from snncc.cli.main import run
    from snncc.ir.serialize import save_graph
    from xylo_models import chain

    d = tmp_path_factory.mktemp("xylo")
    model = d / "chain.snnir"
    save_graph(chain(np.random.default_rng(0), w_scale=1.0), model)
    out = d / "net.xylo"
    assert run(["compile", str(model), "--target", "xylo", "-o", str(out), "--rule", "single", *QUICK]) == 0
    x = (np.random.default_rng(5).random((5, 40, 6)) < 0.2).astype(np.uint8)
    np.save(d / "x.npy", x)
    return model, out, d / "x.npy"


_ORACLES: dict = {}


@pytest.fixture(scope="session")
def xylosim():
    """``xylosim(spec)``: one XyloSim build (``oracle.XyloSimOracle``) per distinct spec file, shared by the session."""
    from tests.xylo.oracle import XyloSimOracle

    def build(spec, key=None):
        key = key if key is not None else id(spec)
        if key not in _ORACLES:
            _ORACLES[key] = (spec, XyloSimOracle(spec))       # the spec kept: its id is never reused meanwhile
        return _ORACLES[key][1]

    return build
