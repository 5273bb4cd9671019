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
