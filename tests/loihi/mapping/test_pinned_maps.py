"""Core maps pinned to what map_network produced before the mapper was split by job
(``pinned_core_maps.json``): the same cores, placements, usage, bounds and text for fixed networks
that take the exact search (the paper's th1 RSNN), fan-in relays, greedy slicing with repair
(a sparse recurrent chain) and equal slicing of layers above GREEDY_MAX_NEURONS (banded)."""

from __future__ import annotations

import functools
import io
import json
from pathlib import Path

import pytest
from rich.console import Console

from snncc.targets.loihi.mapping.coremap import USAGE_FIELDS
from snncc.targets.loihi.mapping.partition import map_network

from .helpers import banded, chain, paper_rsnn

PINNED = json.loads((Path(__file__).parent / "pinned_core_maps.json").read_text())
NETWORKS = {
    "paper_rsnn_th1": lambda: paper_rsnn(seed=0),
    "wide_fan_in_5000_to_100": lambda: chain([5000, 100], seed=1),
    "sparse_recurrent_chain": lambda: chain([300, 2500, 1500], seed=5, density=0.3, rec=(1,)),
    "banded_3x21000": lambda: banded(21000, 3, 64, seed=1),
}


def digest(d: dict) -> dict:
    """The pinned fields of ``CoreMap.to_dict()``; each core as [core, chip, slices, usage]."""
    keep = {k: d[k] for k in PINNED["maps"]["paper_rsnn_th1"] if k != "cores"}
    cores = [[c["core"], c["chip"], [[s["index"], s["start"], s["stop"]] for s in c["layers"]],
              [c[k] for k in USAGE_FIELDS]] for c in d["cores"]]
    return {**keep, "cores": cores}


@functools.cache
def mapped(name: str):
    return map_network(NETWORKS[name]())


@pytest.mark.parametrize("name", sorted(NETWORKS))
def test_core_map_is_the_pinned_one(name):
    cm = mapped(name)
    got = digest(json.loads(json.dumps(cm.to_dict())))
    want = PINNED["maps"][name]
    assert got["n_cores"] == want["n_cores"] and got["lower_bound"] == want["lower_bound"]
    assert got["cores"] == want["cores"]
    assert got == want


@pytest.mark.parametrize("name", sorted(PINNED["text"]))
def test_core_map_text_is_the_pinned_one(name):
    buf = io.StringIO()
    mapped(name).render_text(Console(file=buf, width=120, highlight=False, color_system=None))
    assert buf.getvalue() == PINNED["text"][name]
