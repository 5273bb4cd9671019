"""The layout issues 13, 24 and 37 ask for, checked on the source, function-level imports included: no
import cycle between snncc's modules, the library never imports the CLI or the verbs, snncc/ reaches a
target only through the registry, ``snncc.targets.base``, the kit and the target's registered entry module,
the CLI holds no numerical code (it parses, calls, prints), and snncc/ names no target (the registry's
``DEFAULT_TARGET`` is the one place; the training timing presets may name the paper's chips).

Imports under ``if TYPE_CHECKING:`` are left out: they never run. The tree is parsed once per test session."""

from __future__ import annotations

import ast
import functools
from collections import defaultdict
from importlib.metadata import entry_points
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ((REPO / "snncc", "snncc"), (REPO / "targets", "snncc.targets"))
TARGET_PACKAGES = {p.name for p in (REPO / "targets").iterdir() if (p / "__init__.py").is_file()}
HEAVY = {"numpy", "torch", "scipy", "sklearn", "numba", "h5py", "pandas"}


@functools.lru_cache(maxsize=None)
def _modules() -> tuple[tuple[str, Path], ...]:
    out = {}
    for root, package in PACKAGES:
        for path in root.rglob("*.py"):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([package, *parts])] = path
    return tuple(out.items())


@functools.lru_cache(maxsize=None)
def _parsed(path: Path) -> ast.AST:
    return ast.parse(path.read_text(encoding="utf-8"))


def modules() -> dict[str, Path]:
    """Dotted module name -> source file, for snncc and its targets sub-package (read once per session)."""
    return dict(_modules())


def _type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None)
    return isinstance(node, ast.If) and (
        (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
        or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"))


def import_nodes(tree: ast.AST):
    """Every import statement of ``tree`` at any depth (functions, methods, branches), except those
    under ``if TYPE_CHECKING:``."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        for child in ast.iter_child_nodes(node):
            if _type_checking(child):
                stack.extend(child.orelse)
            else:
                stack.append(child)


def imported(name: str, path: Path, nodes) -> set[str]:
    """Absolute names imported by the import statements among ``nodes`` (relative ones resolved);
    ``from a import b`` gives ``a`` and ``a.b`` (the latter counts only where ``a.b`` is a module)."""
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


def every_import(mods: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the names it imports anywhere (function level included, TYPE_CHECKING excluded)."""
    return {name: imported(name, path, import_nodes(_parsed(path))) for name, path in mods.items()}


def find_cycle(edges: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as a list of modules (first == last), or None."""
    state: dict[str, int] = {}
    trail: list[str] = []

    def visit(u: str) -> list[str] | None:
        state[u] = 1
        trail.append(u)
        for v in sorted(edges.get(u, ())):
            if state.get(v) == 1:
                return trail[trail.index(v):] + [v]
            if v not in state:
                found = visit(v)
                if found:
                    return found
        trail.pop()
        state[u] = 2
        return None

    for m in sorted(edges):
        if m not in state:
            found = visit(m)
            if found:
                return found
    return None


def module_edges(mods: dict[str, Path]) -> dict[str, set[str]]:
    imports = every_import(mods)
    return defaultdict(set, {n: {t for t in ts if t in mods and t != n} for n, ts in imports.items()})


def test_no_import_cycle_function_level_included():
    cycle = find_cycle(module_edges(modules()))
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_the_cycle_finder_finds_a_cycle_through_a_function_level_import(tmp_path):
    """The check can fail: a planted function-level import back into a module's importer is a cycle."""
    mods = modules()
    planted = tmp_path / "synth_v2.py"
    planted.write_text(mods["snncc.data.synth_v2"].read_text(encoding="utf-8")
                       + "\n\ndef _planted():\n    from snncc.data.synth import generate\n", encoding="utf-8")
    cycle = find_cycle(module_edges({**mods, "snncc.data.synth_v2": planted}))
    assert cycle is not None and {"snncc.data.synth", "snncc.data.synth_v2"} <= set(cycle)
    typed = tmp_path / "typed.py"
    typed.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from snncc.data.synth import generate\n",
                     encoding="utf-8")
    assert find_cycle(module_edges({**mods, "snncc.data.synth_v2": typed})) is None


def entry_modules() -> set[str]:
    """The modules snncc's own targets register under the ``snncc.targets`` entry-point group."""
    return {ep.value.partition(":")[0] for ep in entry_points(group="snncc.targets")
            if ep.value.startswith("snncc.targets.")}


def target_internals(imports: dict[str, set[str]], mods: dict[str, Path], allowed: set[str]) -> list[str]:
    """``module -> target module`` for every import from snncc/ (not targets/) of a target's module
    other than the registry, ``snncc.targets.base`` and the registered entry modules."""
    bad = []
    for name, targets in imports.items():
        if name.startswith("snncc.targets"):
            continue
        for t in targets:
            if t.startswith("snncc.targets.") and t in mods and t not in allowed:
                bad.append(f"{name} -> {t}")
    return sorted(bad)


def test_snncc_imports_no_target_internals():
    mods = modules()
    entries = entry_modules()
    assert {"snncc.targets.ir", "snncc.targets.loihi.capabilities", "snncc.targets.jetson.capabilities"} <= entries
    kit = {m for m in mods if m == "snncc.targets.kit" or m.startswith("snncc.targets.kit.")}
    allowed = {"snncc.targets", "snncc.targets.base", *kit, *entries}
    bad = target_internals(every_import(mods), mods, allowed)
    assert not bad, "snncc/ imports a target's internals (ask the target for a capability): " + ", ".join(bad)


def test_the_internals_check_can_fail(tmp_path):
    mods = modules()
    planted = tmp_path / "qat.py"
    planted.write_text("def f():\n    from snncc.targets.loihi.lowering.quantize import weight_scale\n", encoding="utf-8")
    mods = {**mods, "snncc.training.planted": planted}
    kit = {m for m in mods if m == "snncc.targets.kit" or m.startswith("snncc.targets.kit.")}
    bad = target_internals(every_import(mods), mods, {"snncc.targets", "snncc.targets.base", *kit, *entry_modules()})
    assert bad == ["snncc.training.planted -> snncc.targets.loihi.lowering.quantize"]


def test_the_library_never_imports_the_cli_or_the_verbs():
    """Layers: the CLI over ``snncc.api`` over ``snncc.verbs`` over the rest."""
    for name, every in every_import(modules()).items():
        if not name.startswith("snncc.cli"):
            assert not any(t == "snncc.cli" or t.startswith("snncc.cli.") for t in every), f"{name} imports snncc.cli"
        if not name.startswith(("snncc.cli", "snncc.api", "snncc.verbs")):
            up = sorted(t for t in every if t in ("snncc.api", "snncc.verbs") or t.startswith("snncc.verbs."))
            assert not up, f"{name} imports {up}: the verbs sit above the library"


def test_cli_modules_hold_no_numerical_code():
    mods = modules()
    for name, every in every_import(mods).items():
        if not name.startswith("snncc.cli."):
            continue
        heavy = {t.split(".")[0] for t in every} & HEAVY
        assert not heavy, f"{mods[name]} imports {sorted(heavy)}: numerical work belongs in the library"
        internals = [t for t in every if t.startswith("snncc.targets.") and t.split(".")[2] in TARGET_PACKAGES]
        assert not internals, f"{mods[name]} imports a target's internals {internals}: ask the target for a capability"


PRESETS = {"snncc/models/snn.py", "snncc/cli/train_cmd.py"}     # the training timing presets: the paper's chips


def _names_in(path: Path) -> list[str]:
    return [f"{path.name}:{node.lineno} {node.value!r}" for node in ast.walk(_parsed(path))
            if isinstance(node, ast.Constant) and node.value in ("loihi", "jetson", "xylo")]


def target_names_in_core() -> list[str]:
    """``file:line`` of every string literal in snncc/ that is a target's name, outside the training presets (the C
    target's one-letter name is left out: "c" is also an LSTM's cell state)."""
    found = []
    names = {"loihi", "jetson", "xylo"}
    for name, path in modules().items():
        rel = str(path.relative_to(REPO))
        if not rel.startswith("snncc/") or rel in PRESETS:
            continue
        for node in ast.walk(_parsed(path)):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
                found.append(f"{rel}:{node.lineno} {node.value!r}")
    return found


def test_the_core_names_no_target():
    assert target_names_in_core() == []


def test_the_name_scan_can_fail(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text('def f(target="jetson"):\n    return target\n', encoding="utf-8")
    assert any("'jetson'" in line for line in _names_in(planted))


SCRIPTS = ("bench", "examples")     # scripts that use snncc as its users do: public names only
OWN = ("self", "cls", "os", "sys")  # ``self._x`` is the script's own object; ``os._exit``, ``sys._getframe``: not snncc's


def private_uses(path: Path) -> list[str]:
    """``file:line what`` for every private name a script takes from snncc (its targets included): ``from snncc...
    import _name``, an import from or of a private module (``snncc.x._mod``), and ``obj._attr`` on anything but
    ``OWN``."""
    found = []
    for node in ast.walk(_parsed(path)):
        where = f"{path.name}:{getattr(node, 'lineno', 0)}"
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "snncc":
            if any(part.startswith("_") for part in node.module.split(".")):
                found.append(f"{where} from {node.module}")
            found += [f"{where} import {a.name}" for a in node.names if a.name.startswith("_")]
        elif isinstance(node, ast.Import):
            found += [f"{where} import {a.name}" for a in node.names
                      if a.name.split(".")[0] == "snncc" and any(p.startswith("_") for p in a.name.split("."))]
        elif (isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")
              and not (isinstance(node.value, ast.Name) and node.value.id in OWN)):
            found.append(f"{where} .{node.attr}")
    return found


def test_bench_and_examples_use_public_names_only():
    """Issue 37: benches, studies and examples break on no internal refactor: no ``_private`` import from snncc or
    its targets, no private attribute of snncc's objects."""
    bad = [f"{path.parent.relative_to(REPO)}/{line}" for root in SCRIPTS
           for path in sorted((REPO / root).rglob("*.py")) for line in private_uses(path)]
    assert bad == [], "private snncc names in scripts: " + ", ".join(bad)


def test_the_private_name_scan_can_fail(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text("from snncc.targets.xylo.lowering.lower import _fit, lower\nimport snncc.ir._kernel\n"
                       "from snncc.targets.loihi._chip import LIMITS\nimport numpy._core\n\n\nclass A:\n"
                       "    def f(self, net):\n        return self._x, net._layers, os._exit\n", encoding="utf-8")
    assert sorted(private_uses(planted)) == ["planted.py:1 import _fit", "planted.py:2 import snncc.ir._kernel",
                                             "planted.py:3 from snncc.targets.loihi._chip", "planted.py:9 ._layers"]
