"""Session fixtures: the small models lowered once (lowering exports and validates, a few seconds each)."""

from __future__ import annotations

import pytest

from snncc.frontends import graph_from_object
from snncc.targets.jetson import target
from tests.jetson.helpers import MODELS, STEPS


@pytest.fixture(scope="session")
def graphs():
    return {name: graph_from_object(make()) for name, make in MODELS.items()}


@pytest.fixture(scope="session")
def artefacts(graphs, tmp_path_factory):
    """name -> (graph, artefact, written directory)."""
    out = {}
    root = tmp_path_factory.mktemp("jetson")
    for name, g in graphs.items():
        art = target.lower(g, {"time_steps": STEPS})
        art.write(root / name)
        out[name] = (g, art, root / name)
    return out
