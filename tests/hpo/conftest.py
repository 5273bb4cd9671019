"""Fixtures of the HPO tests: a small synthetic Braille directory."""

from __future__ import annotations

import json

import pytest


@pytest.fixture(scope="session")
def braille_dir(tmp_path_factory):
    """27 letters x 7 repetitions (SYNTHETIC, seed 5), threshold-1 events and raw frames, with the marker."""
    from snncc.data import formats
    from snncc.data.sigma_delta import encode
    from snncc.data.braille_files import MARKER
    from snncc.data.synth import generate

    d = tmp_path_factory.mktemp("hpo_braille")
    raw, labels = generate(7, seed=5)
    formats.write_raw(d / formats.RAW_NAME, raw, labels, release=1)
    formats.write_events(d / formats.events_name(1), encode(255 - raw.astype("int64"), 1), labels, release=1)
    (d / MARKER).write_text(json.dumps({"synthetic": True, "seed": 5, "repetitions": 7}))
    return d

