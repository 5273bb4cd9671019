"""Start-up cost: help and bundle-only verbs import no heavy library (checked in a fresh interpreter)."""

from __future__ import annotations

import json
import subprocess
import sys

HEAVY = ("torch", "sklearn", "scipy", "pandas", "onnx", "onnxruntime", "matplotlib", "numba", "optuna", "networkx")
VERBS = ("compile", "inspect", "emulate", "check", "map", "report", "export", "run", "data", "train", "bench",
         "analyse", "hpo")

PROBE = """
import contextlib, io, json, sys
from snncc.cli.main import run
seen = []
for args in {calls!r}:
    with contextlib.redirect_stdout(io.StringIO()):
        code = run(args)
    heavy = sorted({{m.split('.')[0] for m in sys.modules if m.split('.')[0] in {heavy!r}}})
    seen.append({{"args": args, "code": code, "heavy": heavy}})
print(json.dumps(seen))
"""


def run_in_fresh_interpreter(calls: list[list[str]]) -> list[dict]:
    out = subprocess.run([sys.executable, "-c", PROBE.format(calls=calls, heavy=HEAVY)], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_help_of_snncc_and_every_verb_imports_no_heavy_library():
    calls = [["--help"]] + [[verb, "--help"] for verb in VERBS]
    for record in run_in_fresh_interpreter(calls):
        assert record["code"] == 0, record
        assert record["heavy"] == [], f"snncc {' '.join(record['args'])} imported {record['heavy']}"


def test_every_verb_is_registered():
    import typer

    from snncc.cli.main import build_app

    assert set(VERBS) <= set(typer.main.get_command(build_app()).commands)


def test_bundle_verbs_import_no_torch_or_sklearn(tmp_path, small_rsnn_checkpoint, capsys):
    """emulate / map / report on a bundle need numpy, numba and h5py only (not the compiler's stack); emulate not
    numba either: it runs the C kernel (built by the system's compiler), or the numpy statement for a small run
    (``run_bundle.STATEMENT_WORK``) where only numba's kernel could run."""
    import numpy as np

    from snncc_test_helpers import run_cli

    bundle = tmp_path / "b.net"
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", bundle], capsys)
    assert code == 0, err
    x = tmp_path / "x.npy"
    np.save(x, (np.random.default_rng(0).random((2, 30, 48)) < 0.05).astype(np.uint8))
    for args in (["emulate", str(bundle), "-i", str(x), "-o", str(tmp_path / "o.npz")], ["map", str(bundle)],
                 ["report", str(bundle), "--energy", "--samples", "2"]):
        (record,) = run_in_fresh_interpreter([args])
        assert record["code"] == 0, record
        # networkx too: asking every target whether the path is its artefact loads no compiler (the IR's graph)
        assert not set(record["heavy"]) & {"torch", "sklearn", "pandas", "onnx", "onnxruntime", "matplotlib",
                                           "networkx"}, record
        if args[0] == "emulate":   # the C kernel or, for a small run, the numpy statement: numba is not imported
            assert "numba" not in record["heavy"], record


def test_a_verb_builds_only_its_own_command():
    """``snncc VERB ...`` registers VERB alone (the others' modules are not imported) and still runs as
    a sub-command of the group; ``snncc --help`` lists every verb."""
    probe = ("import contextlib, io, json, sys\nfrom snncc.cli.main import run\nout = io.StringIO()\n"
             "with contextlib.redirect_stdout(out):\n    code = run(['map', '--help'])\n"
             "mods = sorted(m for m in sys.modules if m.startswith('snncc.cli.') and m.endswith('_cmd'))\n"
             "print(json.dumps({'code': code, 'mods': mods, 'usage': out.getvalue()}))\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout.strip().splitlines()[-1])
    assert record["code"] == 0
    assert record["mods"] == ["snncc.cli.map_cmd"]
    assert "Usage: snncc map [OPTIONS]" in record["usage"]
