"""Commands that read NIR graphs, IR files and bundles import no torch; a NIR graph compiled for Loihi
imports torch first where the reference simulator runs (each checked in a fresh interpreter)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from snncc_test_helpers import run_cli

NIR = Path(__file__).resolve().parents[1] / "data" / "nir"

HEAVY_SEEN = """
import contextlib, io, json, sys
from snncc.cli.main import run
seen = []
for args in {calls!r}:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = run(args)
    seen.append({{"args": args, "code": code, "heavy": sorted({{m.split('.')[0] for m in sys.modules}} & {{"torch"}})}})
print(json.dumps(seen))
"""


def run_in_fresh_interpreter(calls: list[list[str]]) -> list[dict]:
    """Run each ``snncc`` call in one fresh interpreter; per call its exit status and whether torch was loaded."""
    out = subprocess.run([sys.executable, "-c", HEAVY_SEEN.format(calls=calls)], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])

FIRST_TORCH_IMPORT = """
import contextlib, io, json, sys, traceback
where = []
class Finder:
    def find_spec(self, name, path=None, target=None):
        if name == "torch" and not where:
            where.extend(f"{{f.filename}}:{{f.name}}" for f in traceback.extract_stack()
                         if "snncc" in f.filename or "targets" in f.filename)
        return None
sys.meta_path.insert(0, Finder())
from snncc.cli.main import run
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    code = run({args!r})
print(json.dumps({{"code": code, "where": where}}))
"""


def first_torch_import(args: list[str]) -> dict:
    """Run ``snncc args`` in a fresh interpreter; the stack (snncc frames) at the first import of torch."""
    out = subprocess.run([sys.executable, "-c", FIRST_TORCH_IMPORT.format(args=args)], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_inspect_of_nir_graphs_and_ir_files_imports_no_torch(tmp_path, capsys):
    ir_file = tmp_path / "braille.snnir"
    code, _, err = run_cli(["compile", NIR / "braille_noDelay_noBias_subtract.nir", "-o", ir_file], capsys)
    assert code == 0, err
    calls = [["inspect", str(NIR / "two_lif_neurons.nir"), "--dt", "1e-3"],
             ["inspect", str(NIR / "two_lif_neurons.nir")],          # refused (no dt): the refusal is torch-free too
             ["inspect", str(NIR / "braille_noDelay_noBias_subtract.nir")],
             ["inspect", str(NIR / "cnn_sinabs.nir")],
             ["inspect", str(NIR / "lif_rockpool.nir"), "--json"],
             ["inspect", str(ir_file)]]
    records = run_in_fresh_interpreter(calls)
    assert [r["code"] for r in records] == [0, 2, 0, 0, 0, 0]
    for record in records:
        assert "torch" not in record["heavy"], record


def test_map_report_emulate_of_a_nir_bundle_import_no_torch(tmp_path, capsys):
    bundle = tmp_path / "braille.net"
    code, _, err = run_cli(["compile", NIR / "braille_noDelay_noBias_subtract.nir", "--scale", "global", "-o", bundle],
                           capsys)
    assert code == 0, err
    x = tmp_path / "x.npy"
    np.save(x, (np.random.default_rng(0).random((2, 40, 12)) < 0.1).astype(np.uint8))
    calls = [["map", str(bundle)], ["map", str(bundle), "--plot", str(tmp_path / "map.png")],
             ["report", str(bundle), "--energy", "--samples", "2"],
             ["emulate", str(bundle), "-i", str(x), "-o", str(tmp_path / "out.npz")]]
    for record in run_in_fresh_interpreter(calls):
        assert record["code"] == 0, record
        assert "torch" not in record["heavy"], record


def test_a_nir_graph_compiled_and_checked_for_loihi_imports_no_torch(tmp_path):
    """Loading the graph, looking up the targets (Jetson's included), lowering, mapping and the check against the IR
    reference (numpy) all run without torch: only training and fine-tuning load it."""
    args = ["compile", str(NIR / "braille_noDelay_noBias_subtract.nir"), "--scale", "global",
            "-o", str(tmp_path / "b.net")]
    record = first_torch_import(args)
    assert record["code"] == 0
    assert not record["where"], record["where"]
    record = first_torch_import(["check", str(NIR / "braille_noDelay_noBias_subtract.nir"), "--artefact",
                                 str(tmp_path / "b.net"), "--samples", "20"])
    assert record["code"] == 0 and not record["where"], record["where"]
