"""The target interface holds: mypy checks ``targets/base.py``, the registry, ``snncc/api.py``,
``snncc/verbs/`` and every target's registered entry module (strictly: every definition typed; see
``[tool.mypy]`` in pyproject.toml), none of them silences it with an ignore comment or types anything
as ``typing.Any``.

``targets/`` installs as ``snncc.targets``; mypy reads the source through a tree of links that puts it
there (``TREE/snncc/targets -> targets``), so every import resolves as it does when installed."""

from __future__ import annotations

import re
from importlib.metadata import entry_points
from pathlib import Path

import mypy.api

REPO = Path(__file__).resolve().parents[1]


def checked_files(root: Path) -> list[Path]:
    """The files the check covers, under ``root`` (the tree's ``snncc``)."""
    entries = {ep.value.partition(":")[0] for ep in entry_points(group="snncc.targets")
               if ep.value.startswith("snncc.targets.")}
    files = [root / "targets" / "base.py", root / "targets" / "__init__.py", root / "api.py",
             *sorted((root / "verbs").glob("*.py"))]
    for module in sorted(entries):
        path = root.joinpath(*module.split(".")[1:])
        files.append(path / "__init__.py" if path.is_dir() else path.with_suffix(".py"))
    return files


def linked_tree(tmp: Path) -> Path:
    """``tmp/snncc``: links to every entry of snncc/ and ``targets`` -> the repository's targets/."""
    root = tmp / "snncc"
    root.mkdir()
    for entry in (REPO / "snncc").iterdir():
        if entry.name != "__pycache__":
            (root / entry.name).symlink_to(entry)
    (root / "targets").symlink_to(REPO / "targets")
    return root


def test_the_target_interface_type_checks(tmp_path):
    root = linked_tree(tmp_path)
    files = checked_files(root)
    assert {"capabilities.py", "base.py", "api.py", "compile.py"} <= {f.name for f in files} and len(files) > 20
    lines = [(f"{f.parent.name}/{f.name}:{n}", line) for f in files
             for n, line in enumerate(f.read_text(encoding="utf-8").splitlines(), 1)]
    silenced = [where for where, line in lines if re.search(r"#\s*type:\s*ignore", line)]
    assert not silenced, f"ignore comments in the checked modules: {silenced}"
    blanket = [where for where, line in lines if re.search(r"\bAny\b", line.split("#")[0])]
    assert not blanket, f"typing.Any in the checked modules: {blanket}"
    out, err, status = mypy.api.run([*map(str, files), "--config-file", str(REPO / "pyproject.toml"),
                                     "--cache-dir", str(REPO / ".mypy_cache"), "--no-error-summary",
                                     "--hide-error-context"])
    assert status == 0, (out + err).replace(str(root), "snncc")
