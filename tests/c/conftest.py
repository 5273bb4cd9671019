"""Shared fixtures of the C target's tests: one build cache per session (each C source is compiled once) and one
compiled Braille artefact that the command-line tests share."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture(scope="session")
def build_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("c_builds")


@pytest.fixture(scope="session")
def braille_artefact(tmp_path_factory):
    """The subtract Braille graph compiled by the command line (rule auto, 50 steps per sample)."""
    from snncc.cli.main import run

    from c_test_graphs import NIR_DIR

    where = tmp_path_factory.mktemp("c_braille")
    out = where / "braille_c"
    code = run(["compile", str(NIR_DIR / "braille_noDelay_noBias_subtract.nir"), "--dt", "1e-4", "--reset", "subtract",
                "--target", "c", "--time-steps", "50", "-o", str(out)])
    assert code == 0
    return out
