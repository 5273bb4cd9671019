"""Every refusal is exactly one stderr line ``snncc: error: <file>: <field>: <rule>`` (README, errors).

A representative set of bad invocations runs through the real CLI entry point in ONE child
process (not under pytest, whose warning capture would hide a library warning leaking to stderr):
option-range errors of compile, hpo, train, bench, emulate and report; unknown verbs; a storage
URL; NIR graphs whose loading used to print numpy RuntimeWarnings (tau 0, stride 0); file names
with a newline or ": "; an operating-system refusal. Each stderr must be one line whose file and
field parts hold no ": ", and, for command-line problems, whose file part is the command.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest
import torch

from snncc_test_helpers import without_progress

from snncc.frontends.checkpoint import save_checkpoint
from snncc.models import SNNConfig, SpikingClassifier

LINE = re.compile(r"^snncc: error: (?P<file>(?:(?!: ).)+): (?P<field>(?:(?!: ).)+): (?P<rule>.+)$")

CHILD = r"""
import contextlib, io, json, sys
from snncc.cli.main import run
results = []
for argv in json.load(sys.stdin):
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        code = run(argv)
    results.append([code, err.getvalue()])
sys.stdout.write(json.dumps(results))
"""


def _edit(src, dst, key, data):
    shutil.copy(src, dst)
    with h5py.File(dst, "r+") as f:
        del f[key]
        f.create_dataset(key, data=data)
    return dst


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    """(argv, expected file part or None, expected field part) for each bad invocation."""
    import nir

    d = tmp_path_factory.mktemp("format")
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_inputs=3, n_hidden=8, n_outputs=4, input_copies=1))
    save_checkpoint(model, d / "m.pt", {"dt": 0.005})
    from snncc.cli.main import run

    assert run(["compile", str(d / "m.pt"), "-t", "loihi", "-o", str(d / "m.net")]) == 0
    assert run(["compile", str(d / "m.pt"), "-t", "jetson", "-o", str(d / "jet"), "--time-steps", "20"]) == 0
    np.save(d / "x.npy", np.zeros((2, 20, 3), np.uint8))
    w = np.ones((4, 3))
    graph = nir.NIRGraph(nodes={
        "input": nir.Input(input_type={"input": np.array([3])}), "fc": nir.Affine(weight=w, bias=np.zeros(4)),
        "lif": nir.CubaLIF(tau_syn=np.full(4, 0.005), tau_mem=np.full(4, 0.02), r=np.full(4, 20.0),
                           v_leak=np.zeros(4), v_threshold=np.ones(4), w_in=np.full(4, 5.0)),
        "output": nir.Output(output_type={"output": np.array([4])}),
    }, edges=[("input", "fc"), ("fc", "lif"), ("lif", "output")])
    nir.write(str(d / "g.nir"), graph)
    _edit(d / "g.nir", d / "tau0.nir", "node/nodes/lif/tau_mem", np.zeros(4))
    conv = nir.NIRGraph(nodes={
        "input": nir.Input(input_type={"input": np.array([1, 8, 8])}),
        "conv": nir.Conv2d(input_shape=(8, 8), weight=np.ones((2, 1, 3, 3)), stride=1, padding=0, dilation=1,
                           groups=1, bias=np.zeros(2)),
        "flat": nir.Flatten(input_type={"input": np.array([2, 6, 6])}, start_dim=0),
        "lif": nir.IF(r=np.ones(72), v_threshold=np.ones(72)),
        "output": nir.Output(output_type={"output": np.array([72])}),
    }, edges=[("input", "conv"), ("conv", "flat"), ("flat", "lif"), ("lif", "output")])
    nir.write(str(d / "c.nir"), conv)
    _edit(d / "c.nir", d / "stride0.nir", "node/nodes/conv/stride", np.array([0, 0]))
    _edit(d / "c.nir", d / "complex.nir", "node/nodes/conv/weight", np.ones((2, 1, 3, 3)) * (1 + 1j))
    odd = d / "we\nird: name.pt"
    shutil.copy(d / "m.pt", odd)
    (d / "plain.txt").write_text("a file, not a directory")
    o = str(d / "o.snnir")
    s = str
    return [
        (["frobnicate"], "snncc", "frobnicate"),
        (["hpo", "frob"], "snncc hpo", "frob"),
        (["compile"], "snncc compile", None),
        (["compile", s(d / "m.pt"), "-o", o, "--no-such-option"], "snncc compile", "--no-such-option"),
        (["train", "rsnn", "--data", s(d), "-o", o, "--epochs", "many"], "snncc train", "--epochs"),
        (["train", "rsnn", "--data", s(d), "-o", o, "--threads", "0"], "snncc train", "--threads"),
        (["compile", s(d / "m.pt"), "-t", "ir", "-o", o, "--scale", "global"], "snncc compile", "--scale"),
        (["compile", s(d / "m.pt"), "-t", "loihi", "-o", s(d / "o.net"), "--scale", "bogus"], "snncc compile", "--scale"),
        (["hpo", "run", "s", "--data", s(d), "--threads", "0", "--dir", s(d / "w")], "snncc hpo run", "--threads"),
        (["hpo", "run", "s", "--data", s(d), "--step", "both", "--trials", "0", "--dir", s(d / "w")],
         "snncc hpo run", "--trials"),
        (["hpo", "run", "s", "--data", s(d), "--storage", "sqlite:////no/such/dir/x.db"], "/no/such/dir/x.db",
         "--storage"),
        (["hpo", "report", "s", "--storage", f"sqlite:///{d / 'none' / 'x.db'}"], None, "--storage"),
        (["bench", s(d / "jet"), "--samples", "0"], "snncc bench", "--samples"),
        (["emulate", s(d / "m.net"), "-i", s(d / "x.npy"), "-o", s(d / "o.npz"), "--gap", "5"], "snncc emulate", "--gap"),
        (["report", s(d / "m.net"), "--limit", "3"], "snncc report", "--limit"),
        (["data", "synth", "-o", o, "--release", "3"], "snncc data synth", "--release"),
        (["compile", s(d / "tau0.nir"), "-o", o, "--dt", "0.001"], s(d / "tau0.nir"), "node 'lif'.tau_mem"),
        (["compile", s(d / "tau0.nir"), "-o", o], s(d / "tau0.nir"), "node 'lif'.tau_mem"),
        (["compile", s(d / "stride0.nir"), "-o", o], s(d / "stride0.nir"), "node 'conv'.stride"),
        (["compile", s(d / "complex.nir"), "-o", o], s(d / "complex.nir"), "node 'conv'.weight"),
        (["compile", s(d / "no\nsuch.pt"), "-o", o], s(d / "no\\nsuch.pt"), "model"),
        (["compile", s(odd), "-t", "ir", "-o", o, "--dt", "0.001"], s(d / "we\\nird:\\x20name.pt"), "--dt"),
        (["compile", s(d / "m.pt"), "-o", s(d / "plain.txt" / "o.snnir")], s(d / "plain.txt" / "o.snnir"), "output"),
        (["emulate", s(d / "m.net"), "-i", s(d / "x.npy"), "-o", s(d / "plain.txt" / "o.npz")], s(d / "plain.txt"),
         "EEXIST"),
    ]


def test_every_refusal_is_one_three_part_line(cases, tmp_path):
    argvs = [argv for argv, _, _ in cases]
    proc = subprocess.run([sys.executable, "-c", CHILD], input=json.dumps(argvs), capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0 and not proc.stderr, proc.stderr[-3000:]
    results = json.loads(proc.stdout)
    wrong = []
    for (argv, file, field), (code, err) in zip(cases, results):
        lines = without_progress(err).splitlines()
        match = LINE.match(lines[0]) if len(lines) == 1 else None
        if code != 2 or match is None or "sqlite://" in match["file"] \
                or (file is not None and match["file"] != file) or (field is not None and match["field"] != field):
            wrong.append((argv[:2], code, err))
    assert not wrong, "\n".join(map(repr, wrong))


def test_every_option_refusal_in_the_code_names_a_field():
    """A source scan: every SnnccError the code raises states its field (the second part)."""
    import ast
    from pathlib import Path

    import snncc

    roots = [Path(snncc.__file__).parent, Path(snncc.__file__).parent.parent / "targets"]
    missing = []
    for root in roots:
        for path in root.rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "SnnccError":
                    if "field" not in {k.arg for k in node.keywords} and not any(
                            isinstance(a, ast.Starred) for a in node.args):
                        missing.append(f"{path.relative_to(root.parent)}:{node.lineno}")
    assert not missing, missing
