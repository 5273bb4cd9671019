"""snncc bench of several artefacts: progress over every artefact's protocol reaches the caller and
the CLI, and the table says which inputs were SYNTHETIC."""

from __future__ import annotations

import io

from rich.console import Console

from snncc_test_helpers import run_cli

PROTOCOL = {"samples": 3, "repeats": 2, "warmup_passes": 1, "timed_passes": 1}


def test_bench_of_several_artefacts_reports_progress(artefacts):
    import snncc.api

    dirs = [artefacts["rsnn"][2], artefacts["lstm"][2]]
    calls = []
    result = snncc.api.bench(dirs, progress=lambda done, total, phase: calls.append((done, total, phase)),
                             **PROTOCOL)
    per_artefact = (1 + 1 * 2) * 3       # (warm-up passes + timed passes x repeats) x samples
    assert calls, "no progress reported"
    assert {total for _, total, _ in calls} == {2 * per_artefact}
    assert [done for done, _, _ in calls] == sorted(done for done, _, _ in calls) and calls[-1][0] == 2 * per_artefact
    phases = {phase for _, _, phase in calls}
    assert {"rsnn: warm-up", "rsnn: timing", "lstm: warm-up", "lstm: timing"} <= phases
    assert len(result.as_dict()["models"]) == 2


def test_bench_table_says_its_inputs_are_synthetic(artefacts, capsys, monkeypatch):
    import snncc.cli.output as output

    err = io.StringIO()
    monkeypatch.setattr(output, "err_console", Console(file=err, force_terminal=True, width=200))
    dirs = [artefacts["rsnn"][2], artefacts["lstm"][2]]
    args = ["bench", *map(str, dirs)] + [x for k, v in PROTOCOL.items() for x in (f"--{k.replace('_', '-')}", str(v))]
    code, out, _ = run_cli(args, capsys)
    assert code == 0
    header, _, *rows = [line for line in out.splitlines() if line.startswith("|")]
    assert "| inputs |" in header
    assert len(rows) == 2 and all("| SYNTHETIC (random) |" in row for row in rows), rows
    assert "note: inputs SYNTHETIC (random): seeded random inputs" in out
    assert "lstm: timing" in err.getvalue()          # the bar reached the terminal with the protocol's phase
