"""The plug-in boundary, sealed: an out-of-tree target that imports from snncc only ``snncc.targets.base``, the kit
and the IR (``outside_target_source.py``) is installed from a temporary dist-info and driven through compile,
check (with and without ``--artefact``), emulate and ``snncc.api``; a target whose option is named like a command's
own parameter is refused alone, in one line, and every other target keeps working."""

from __future__ import annotations

import ast
import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

import snncc.api as api
from snncc_test_helpers import run_cli

HERE = Path(__file__).resolve().parent
ALLOWED = ("snncc.targets.base", "snncc.targets.kit", "snncc.ir")


def snncc_imports(source: str) -> list[str]:
    """Every module name under ``snncc`` that ``source`` imports (top level or inside functions)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found += [a.name for a in node.names if a.name.split(".")[0] == "snncc"]
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "snncc":
            found += [node.module] if node.level == 0 else []
    return found


def outside(name: str) -> list[str]:
    return [m for m in snncc_imports(name) if not any(m == a or m.startswith(a + ".") for a in ALLOWED)]


def install(root: Path, source: str, module: str, entry: str) -> None:
    shutil.copy(HERE / source, root / f"{module}.py")
    info = root / f"{module}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {module}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[snncc.targets]\n{entry} = {module}:target\n")


@pytest.fixture
def f32(tmp_path, monkeypatch):
    root = tmp_path / "site"
    root.mkdir()
    install(root, "outside_target_source.py", "snncc_f32", "f32")
    monkeypatch.syspath_prepend(str(root))
    yield root
    sys.modules.pop("snncc_f32", None)


def test_the_outside_target_imports_only_base_kit_and_the_ir():
    source = (HERE / "outside_target_source.py").read_text()
    assert snncc_imports(source), "the test target must use the kit"
    assert outside(source) == []
    assert outside("from snncc.artefacts import identify\nimport snncc.atomic") == ["snncc.artefacts", "snncc.atomic"]


@pytest.fixture
def model(tmp_path):
    from snncc.frontends.builders import snn_graph
    from snncc.ir.serialize import save_graph

    rng = np.random.default_rng(3)
    graph = snn_graph(rng.normal(0, 0.6, (8, 20)), rng.normal(0, 0.5, (20, 5)), rng.normal(0, 0.15, (20, 20)),
                      dt=0.005, tau_syn=0.006, tau_mem=0.06, threshold=1.0, metadata={"recording_length_s": 0.1})
    path = tmp_path / "m.snnir"
    save_graph(graph, path)
    return path


def test_compile_check_emulate_and_the_api_drive_the_outside_target(f32, model, tmp_path, capsys):
    out = tmp_path / "m.f32.d"             # a two-part suffix names the target
    code, stdout, err = run_cli(["compile", model, "-o", out, "--f32-chunk", "8", "--json"], capsys)
    assert code == 0, err
    compiled = json.loads(stdout)
    assert compiled["target"] == "f32" and "suffix '.f32.d'" in compiled["target_rule"]
    x = tmp_path / "x.npy"
    np.save(x, (np.random.default_rng(0).random((3, 20, 8)) < 0.3).astype(np.uint8))
    code, stdout, err = run_cli(["emulate", out, "-i", x, "-o", tmp_path / "e.npz", "--json"], capsys)
    assert code == 0, err
    assert json.loads(stdout)["target"] == "f32" and np.load(tmp_path / "e.npz")["output_spikes"].shape[:2] == (3, 20)
    code, stdout, err = run_cli(["check", model, "--artefact", out, "--samples", "16", "--json"], capsys)
    assert code == 0, err
    given = json.loads(stdout)
    assert given["target"] == "f32" and given["argmax_agreement"] is not None or given["argmax"]["decided"] == 0
    assert given["artefact"]["sha256"] == compiled["sha256"]
    code, stdout, err = run_cli(["check", model, "--target", "f32", "--samples", "16", "--json"], capsys)
    assert code == 0, err
    here = json.loads(stdout)
    assert here["artefact"]["sha256"] == compiled["sha256"] and here["argmax"] == given["argmax"]
    record = api.check(model, target="f32", samples=16)
    assert record.as_dict()["argmax"] == given["argmax"]
    assert api.compile(model, output=tmp_path / "api.f32.d").target == "f32"


def test_a_plugin_option_named_like_a_command_parameter_is_refused_alone(tmp_path, monkeypatch, model, capsys):
    root = tmp_path / "site"
    root.mkdir()
    source = (HERE / "outside_target_source.py").read_text().replace("f32_chunk", "reset").replace(
        'name = "f32"', 'name = "clash"').replace('output_suffix = ".f32.d"', 'output_suffix = ".clash"')
    (root / "snncc_clash.py").write_text(source)
    info = root / "snncc_clash-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: snncc_clash\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[snncc.targets]\nclash = snncc_clash:target\n")
    monkeypatch.syspath_prepend(str(root))
    try:
        code, _, err = run_cli(["compile", model, "--target", "ir", "-o", tmp_path / "m2.snnir"], capsys)
        assert code == 0, err                                   # every other target keeps working
        code, _, err = run_cli(["compile", model, "--target", "clash", "-o", tmp_path / "m.clash"], capsys)
        (line,) = err.strip().splitlines()
        assert code == 2 and line.startswith("snncc: error: snncc compile: --target: target 'clash' declares --reset"), line
        assert not (tmp_path / "m.clash").exists()
    finally:
        sys.modules.pop("snncc_clash", None)


def test_every_built_in_target_imports_only_base_kit_the_ir_and_itself():
    root = HERE.parents[1] / "targets"
    bad = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root)
        if rel.parts[0] == "kit" or rel.name in ("__init__.py", "base.py") and len(rel.parts) == 1:
            continue
        own = "snncc.targets." + rel.parts[0]
        found = [m for m in outside(path.read_text()) if not (m == own or m.startswith(own + "."))]
        if found:
            bad[str(rel)] = found
    assert bad == {}
