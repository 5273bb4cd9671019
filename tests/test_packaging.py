"""Packaging: every sub-package is installed, targets are reachable through entry points."""

import tomllib
from pathlib import Path

from snncc.targets import available_targets, get_target

ROOT = Path(__file__).resolve().parents[1]


def test_every_package_directory_is_listed_in_pyproject():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = set()
    for init in ROOT.glob("snncc/**/__init__.py"):
        found.add(".".join(init.parent.relative_to(ROOT).parts))
    for init in ROOT.glob("targets/**/__init__.py"):
        found.add(".".join(("snncc",) + init.parent.relative_to(ROOT).parts))
    assert found <= listed, f"add to pyproject packages: {sorted(found - listed)}"


def test_every_file_besides_python_modules_in_the_packages_is_package_data():
    """A non-Python file in a package directory (the C kernel's source) must be installed with it: listed in
    [tool.setuptools.package-data] under its package, or a non-editable install would lack it."""
    import fnmatch
    import subprocess

    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    tracked = subprocess.run(["git", "ls-files", "snncc", "targets"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.split()
    others = [Path(p) for p in tracked if not p.endswith(".py")]
    assert others, "the C kernel's source is expected among the package files"
    for path in others:
        parts = path.parent.parts
        package = ".".join(("snncc",) + parts) if parts[0] == "targets" else ".".join(parts)
        assert any(fnmatch.fnmatch(path.name, pattern) for pattern in data.get(package, [])), \
            f"add {path.name} to [tool.setuptools.package-data] {package!r}"


def test_targets_register_through_entry_points():
    assert {"ir", "loihi", "jetson"} <= set(available_targets())
    for name in ("ir", "loihi", "jetson"):
        assert get_target(name).name == name


def test_atomic_writes_leave_no_temporaries_and_normal_modes(tmp_path):
    import os

    import pytest

    from snncc.atomic import atomic_dir, atomic_path, write_text_atomic

    write_text_atomic(tmp_path / "a.txt", "hello")
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o666 & ~mask
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "b.bin") as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("crash while writing")
    with pytest.raises(KeyboardInterrupt):
        with atomic_dir(tmp_path / "d") as tmp:
            (tmp / "x").write_text("half")
            raise KeyboardInterrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt"]
    with atomic_dir(tmp_path / "d") as tmp:
        (tmp / "x").write_text("whole")
    assert (tmp_path / "d" / "x").read_text() == "whole"
