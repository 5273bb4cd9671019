"""The layout issue 13 asks for, checked on the source: no import cycle between snncc's modules, the
library never imports the CLI, and the CLI holds no numerical code (it parses, calls, prints)."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ((REPO / "snncc", "snncc"), (REPO / "targets", "snncc.targets"))
TARGET_PACKAGES = {p.name for p in (REPO / "targets").iterdir() if (p / "__init__.py").is_file()}


def modules() -> dict[str, Path]:
    """Dotted module name -> source file, for snncc and its targets sub-package."""
    out = {}
    for root, package in PACKAGES:
        for path in root.rglob("*.py"):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package, *parts])] = path
    return out


def imported(name: str, path: Path, nodes) -> set[str]:
    """Absolute names imported by the import statements among ``nodes`` (relative ones resolved)."""
    names = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = name.split(".")[: len(name.split(".")) - node.level + (path.name == "__init__.py")]
                base = ".".join(parts + ([node.module] if node.module else []))
            names.add(base)
            names.update(f"{base}.{a.name}" for a in node.names)
    return names


def test_no_module_level_import_cycle():
    mods = modules()
    edges = defaultdict(set)
    for name, path in mods.items():
        body = ast.parse(path.read_text(encoding="utf-8")).body   # module level (not TYPE_CHECKING blocks)
        edges[name] = {t for t in imported(name, path, body) if t in mods and t != name}
    state: dict[str, int] = {}
    trail: list[str] = []

    def visit(u: str) -> None:
        state[u] = 1
        trail.append(u)
        for v in sorted(edges[u]):
            assert state.get(v) != 1, "import cycle: " + " -> ".join(trail[trail.index(v):] + [v])
            if v not in state:
                visit(v)
        trail.pop()
        state[u] = 2

    for m in sorted(mods):
        if m not in state:
            visit(m)


def test_the_library_never_imports_the_cli():
    for name, path in modules().items():
        if name.startswith("snncc.cli"):
            continue
        every = imported(name, path, ast.walk(ast.parse(path.read_text(encoding="utf-8"))))
        assert not any(t == "snncc.cli" or t.startswith("snncc.cli.") for t in every), f"{path} imports snncc.cli"


def test_cli_modules_hold_no_numerical_code():
    for name, path in modules().items():
        if not name.startswith("snncc.cli."):
            continue
        every = imported(name, path, ast.walk(ast.parse(path.read_text(encoding="utf-8"))))
        heavy = {t.split(".")[0] for t in every} & {"numpy", "torch", "scipy", "sklearn", "numba", "h5py", "pandas"}
        assert not heavy, f"{path} imports {sorted(heavy)}: numerical work belongs in the library"
        internals = [t for t in every if t.startswith("snncc.targets.") and t.split(".")[2] in TARGET_PACKAGES]
        assert not internals, f"{path} imports a target's internals {internals}: ask the target for a capability"
