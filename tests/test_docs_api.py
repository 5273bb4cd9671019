"""docs/api.md's pipeline block runs as written (the Python equivalent of the README's commands)."""

from __future__ import annotations

import re
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def example_block() -> str:
    text = DOC.read_text(encoding="utf-8")
    match = re.search(r"<!-- api-example -->\n```python\n(.*?)```", text, re.S)
    assert match, "docs/api.md lost its <!-- api-example --> block"
    return match.group(1)


def test_api_example_runs_as_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    exec(compile(example_block(), str(DOC), "exec"), {"__name__": "docs_api_example"})
    for written in ("braille", "events.npz", "rsnn.pt", "rsnn.net", "rsnn.snnir", "rsnn.nir", "out.npz"):
        assert (tmp_path / written).exists(), written
    out = capsys.readouterr().out
    assert "wrote rsnn.net" in out


def _parses(argv: list[str]) -> None:
    """Parse ``snncc argv`` with the real command (options and arguments checked), without running it."""
    import typer

    from snncc.cli.main import build_app

    command = typer.main.get_command(build_app(argv))
    names = []
    while hasattr(command, "commands") and argv and argv[0] in command.commands:
        names.append(argv[0])
        command, argv = command.commands[argv[0]], argv[1:]
    command.make_context(" ".join(["snncc", *names]), list(argv))


def test_the_commands_beside_the_api_example_exist_as_written():
    """Each ``# snncc ...`` comment of the api-example block parses (no option the command lacks)."""
    import shlex

    commands = [line.split("# snncc ", 1)[1] for line in example_block().splitlines() if "# snncc " in line]
    assert len(commands) >= 12
    for text in commands:
        if "..." in text:
            continue                     # an elided command ('snncc train ... --json')
        _parses(shlex.split(text))


def test_the_notes_paragraph_says_what_each_record_holds(tmp_path, small_rsnn_checkpoint):
    import snncc.api as api
    from snncc.frontends import import_notes

    text = DOC.read_text(encoding="utf-8")
    assert "`compile`'s record has no `notes`" in text and "import_notes(record.graph)" in text
    record = api.compile(small_rsnn_checkpoint, target="ir", output=tmp_path / "m.snnir")
    assert not hasattr(record, "notes") and isinstance(import_notes(record.graph), list)
    assert hasattr(api.inspect(small_rsnn_checkpoint), "notes")
