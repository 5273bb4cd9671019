"""Left-overs of the hostile-input probe: a refused ``hpo run`` creates no storage, ``inspect`` of a
Loihi bundle says what it is, and ``wrote <name>`` lines keep a hostile name on one line."""

from __future__ import annotations

import re

import pytest

from snncc_test_helpers import run_cli, small_rsnn


def _error_line(code: int, err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and lines[0].startswith("snncc: error: "), err
    return lines[0]


@pytest.mark.parametrize("existing_dir", [False, True])
def test_a_refused_hpo_run_leaves_no_storage_behind(tmp_path, capsys, existing_dir):
    """27 samples cannot be split stratified by 27 classes: refused before the study's storage is opened."""
    import snncc.api as api

    api.data_synth(out=tmp_path / "br", repetitions=1, thresholds="1")
    work = tmp_path / "w"
    if existing_dir:
        work.mkdir()
    code, _, err = run_cli(["hpo", "run", "s", "--data", tmp_path / "br", "--dir", work, "--quiet"], capsys)
    assert "cannot split" in _error_line(code, err)
    assert work.exists() == existing_dir
    assert not existing_dir or list(work.iterdir()) == []


def test_hpo_report_of_a_missing_sqlite_storage_creates_none(tmp_path, capsys):
    db = tmp_path / "none.db"
    code, _, err = run_cli(["hpo", "report", "s", "--storage", f"sqlite:///{db}", "--no-plot"], capsys)
    assert _error_line(code, err).startswith(f"snncc: error: {db}: --storage: ")
    assert not db.exists()


def test_inspect_of_a_loihi_bundle_says_what_it_is_and_which_commands_read_it(tmp_path, capsys):
    small_rsnn(tmp_path / "m.pt")
    assert run_cli(["compile", tmp_path / "m.pt", "-t", "loihi", "-o", tmp_path / "x.net"], capsys)[0] == 0
    for verb in ("inspect", "export"):
        args = [verb, tmp_path / "x.net"] + (["-o", tmp_path / "x.nir"] if verb == "export" else [])
        line = _error_line(*run_cli(args, capsys)[::2])
        assert "is a Loihi bundle" in line and all(f"snncc {v}" in line for v in ("emulate", "map", "report")), line


@pytest.mark.parametrize("name", ["two\nlines.snnir", "esc\x1b[31mred.snnir", "[bold]markup[/bold].snnir"])
def test_wrote_lines_keep_a_hostile_name_on_one_escaped_line(tmp_path, capsys, name):
    from snncc.errors import one_line

    small_rsnn(tmp_path / "m.pt")
    code, out, err = run_cli(["compile", tmp_path / "m.pt", "-t", "ir", "-o", tmp_path / name], capsys)
    assert code == 0, err
    assert (tmp_path / name).is_file()
    wrote = [line for line in out.splitlines() if line.startswith("wrote ")]
    assert len(wrote) == 1 and re.fullmatch(re.escape(f"wrote {one_line(str(tmp_path / name))}")
                                            + r" \(SHA-256 [0-9a-f]{64}\)", wrote[0]), out
