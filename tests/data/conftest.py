"""Fixtures of the Braille data tests: a small synthetic set in the published layout."""

from __future__ import annotations

import pytest


def cli(args, capsys) -> tuple[int, str, str]:
    """Run ``snncc args`` in-process; (exit status, stdout, stderr)."""
    from snncc.cli.main import run

    capsys.readouterr()
    code = run([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="session")
def small_set(tmp_path_factory):
    """27 letters x 3 repetitions written by the generator (release 1 layout) + its arrays."""
    from snncc.data import formats
    from snncc.data.sigma_delta import encode
    from snncc.data.synth import generate

    d = tmp_path_factory.mktemp("braille_small")
    raw, labels = generate(3, seed=3)
    formats.write_raw(d / formats.RAW_NAME, raw, labels, release=1)
    x = 255 - raw.astype("int64")
    for th in formats.THRESHOLDS:
        formats.write_events(d / formats.events_name(th), encode(x, th), labels, release=1)
    return d, raw, labels
