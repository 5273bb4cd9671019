"""Long steps say what they are doing outside a terminal too: one line on stderr when a phase starts and at most
every 10 s within it (``snncc: progress: <phase>: <done>/<total>``), never on stdout; with --json (a tool reading the
record) nothing but the record and errors is printed."""

from __future__ import annotations

import json

from snncc_test_helpers import PROGRESS, run_cli


def test_a_compile_in_a_pipe_prints_a_line_per_phase(tmp_path, capsys, shared_nir):
    args = ["compile", shared_nir / "braille_zero_2023.nir", "--dt", "1e-4", "--target", "loihi", "-o", tmp_path / "z.net"]
    code, stdout, err = run_cli(args + ["--json"], capsys, progress=True)
    assert code == 0 and PROGRESS not in err, err
    json.loads(stdout)                                   # stdout holds the record alone
    code, stdout, err = run_cli(args, capsys, progress=True)
    assert code == 0 and PROGRESS not in stdout
    lines = [line for line in err.splitlines() if line.startswith(PROGRESS)]
    phases = [line.split(": ")[2] for line in lines]
    assert len(lines) >= 1 and len(set(phases)) == len(phases), err      # one line per phase here (< 10 s each)
    assert all(line.rsplit(": ", 1)[1].count("/") == 1 for line in lines)


def test_the_interval_within_a_phase(monkeypatch, capsys):
    from snncc.cli import output

    clock = iter([0.0, 1.0, 2.0, 12.0, 13.0, 30.0])
    monkeypatch.setattr("time.monotonic", lambda: next(clock))
    with output.progress_bar() as progress:
        for done in range(5):
            progress(done, 10, "emulating")
        progress(0, 1, "writing")
    lines = capsys.readouterr().err.splitlines()
    assert lines == ["snncc: progress: emulating: 0/10", "snncc: progress: emulating: 3/10",
                     "snncc: progress: writing: 0/1"]
