"""The Loihi target imports from snncc only the interface, the kit, the IR and itself: every import in
``targets/loihi/``, at module level or inside a function, is checked."""

from __future__ import annotations

import ast
from pathlib import Path

import snncc.targets.loihi as loihi

ROOT = Path(loihi.__file__).parent
ALLOWED = ("snncc.targets.base", "snncc.targets.kit", "snncc.ir", "snncc.targets.loihi")


def imports(path: Path) -> list[tuple[int, str]]:
    """(line, module) of every ``import`` / ``from ... import`` of an ``snncc`` module in ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names = [f"{node.module}.{a.name}" for a in node.names] if node.module == "snncc.targets" else [node.module]
            found += [(node.lineno, n) for n in names]
    return [(line, m) for line, m in found if m == "snncc" or m.startswith("snncc.")]


def outside(module: str) -> bool:
    return not any(module == a or module.startswith(a + ".") for a in ALLOWED)


def test_every_loihi_module_imports_only_the_interface_the_kit_the_ir_and_itself():
    bad = [f"{path.relative_to(ROOT)}:{line}: {m}" for path in sorted(ROOT.rglob("*.py"))
           for line, m in imports(path) if outside(m)]
    assert not bad, "imports outside the kit boundary: " + ", ".join(bad)


def test_the_boundary_check_can_fail(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text("def f():\n    from snncc.targets import get_target\n    import snncc.errors\n"
                       "    from snncc.targets.kit import SnnccError\n", encoding="utf-8")
    assert [m for _, m in imports(planted) if outside(m)] == ["snncc.targets.get_target", "snncc.errors"]


def test_no_loihi_module_is_over_500_lines():
    long = {str(p.relative_to(ROOT)): n for p in ROOT.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > 500}
    assert not long, long
