"""Fixtures the Loihi tests share: a bundle compiled once per session (tests that only read it take it as it is;
a test that edits one copies it first)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def authors_layout_bundle(tmp_path_factory) -> tuple[Path, Path, Path]:
    """(weights, parameters file, bundle): an authors'-layout weight list (48 input axons = 24 event channels x 2
    copies -> 24 recurrent -> 28, seed 2) compiled once with the th1 parameters: ``snncc compile w.pt --params
    parameters_th1.txt --target loihi -o m.net``."""
    import torch

    from snncc.cli.main import run
    from snncc_test_helpers import TH1_PARAMS

    folder = tmp_path_factory.mktemp("authors_layout")
    g = torch.Generator().manual_seed(2)
    weights = folder / "w.pt"
    torch.save([torch.randn(48, 24, generator=g) * 0.5, torch.randn(24, 28, generator=g) * 0.5,
                torch.randn(24, 24, generator=g) * 0.1], weights)
    params = folder / "parameters_th1.txt"
    params.write_text(TH1_PARAMS)
    bundle = folder / "m.net"
    assert run(["compile", str(weights), "--params", str(params), "--target", "loihi", "-o", str(bundle)]) == 0
    return weights, params, bundle
