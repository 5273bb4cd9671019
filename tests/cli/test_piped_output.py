"""Output that survives a pipe: when stdout is not a terminal, no line is wrapped and no table cell cut.

The commands run in a child process whose stdout is a pipe (no COLUMNS in its environment), on
files under a directory nested more than 200 characters deep, as text and as ``--json``.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys

import pytest

from snncc_test_helpers import build_workspace

CHILD = r"""
import json, sys
from snncc.cli.main import run
for argv in json.load(sys.stdin):
    sys.stdout.write("\x00begin\n"); sys.stdout.flush()
    code = run(argv)
    sys.stdout.flush()
    sys.stdout.write(f"\x00end {code}\n"); sys.stdout.flush()
"""


@pytest.fixture(scope="module")
def deep(tmp_path_factory):
    d = tmp_path_factory.mktemp("piped")
    for part in ("a" * 50, "b" * 50, "c" * 50, "d" * 50, "e" * 50):
        d = d / part
    d.mkdir(parents=True)
    assert len(str(d)) > 250
    build_workspace(d)
    return d


def commands(d) -> dict[str, list[str]]:
    s = str
    return {
        "compile": ["compile", s(d / "m.pt"), "-t", "loihi", "-o", s(d / "out.net")],
        "emulate": ["emulate", s(d / "b.net"), "-i", s(d / "spikes.npy"), "-o", s(d / "out.npz")],
        "map": ["map", s(d / "b.net"), "--plot", s(d / "cores.png")],
        "report": ["report", s(d / "b.net"), "--energy", "--samples", "2"],
        "check": ["check", s(d / "m.pt"), "--data", s(d / "ev.npz"), "--limit", "4"],
        "data synth": ["data", "synth", "-o", s(d / "syn"), "-n", "1", "--thresholds", "1"],
        "data encode": ["data", "encode", s(d / "br"), "-t", "1", "-o", s(d / "enc.npz")],
        "train": ["train", "rsnn", "--data", s(d / "ev.npz"), "--epochs", "1", "-o", s(d / "t.pt"), "--quiet"],
        "export": ["export", s(d / "m.pt"), "-o", s(d / "m.nir")],
        "inspect": ["inspect", s(d / "m.pt")],
    }


def run_piped(argvs: list[list[str]]) -> list[tuple[int, str]]:
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES", "FORCE_COLOR", "TTY_COMPATIBLE")}
    env.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", NUMBA_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-c", CHILD], input=json.dumps(argvs), capture_output=True, text=True,
                          env=env, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    results = []
    for chunk in proc.stdout.split("\x00begin\n")[1:]:
        body, _, status = chunk.rpartition("\x00end ")
        results.append((int(status.strip()), body))
    assert len(results) == len(argvs), proc.stdout[-2000:]
    return results


@pytest.fixture(scope="module")
def piped(deep):
    names = list(commands(deep))
    argvs = [commands(deep)[n] for n in names] + [commands(deep)[n] + ["--json"] for n in names]
    results = run_piped(argvs)
    return deep, dict(zip(names, results[:len(names)])), dict(zip(names, results[len(names):]))


def _line_with(out: str, *parts: str) -> str:
    """The one line holding every part (fails if the parts are spread over lines or missing)."""
    found = [line for line in out.splitlines() if all(p in line for p in parts)]
    assert found, f"no single line holds {parts!r} in:\n{out}"
    return found[0]


@pytest.mark.parametrize("name", ["compile", "emulate", "map", "report", "check", "data synth", "data encode",
                                  "train", "export", "inspect"])
def test_text_output_is_whole_when_piped(piped, name):
    d, text, _ = piped
    code, out = text[name]
    assert code == 0, out
    assert "…" not in out, out        # rich's mark of a cut cell
    written = {"compile": "out.net", "emulate": "out.npz", "map": "cores.png", "data synth": "syn",
               "data encode": "enc.npz", "train": "t.pt", "export": "m.nir"}
    if name in written:
        _line_with(out, str(d / written[name]))
    if name == "inspect":      # the widest table: every cell whole, one row per line
        _line_with(out, "w_in", "shape=[32, 48], parameters=1536, max_abs_weight=", "bias=False")
        _line_with(out, "hidden", "tau_syn=0.006", "discretisation=exp, bias=None")
    if name == "map":
        _line_with(out, "hidden[0:32], out[0:28]", "37,888 (3.6%)")
    if name == "report":
        _line_with(out, "energy per sample (uJ)", "71.0")
        _line_with(out, "power (mW)", "(dynamic only)", "31.0 (total)")


@pytest.mark.parametrize("name", ["compile", "emulate", "map", "report", "check", "data synth", "data encode",
                                  "train", "export", "inspect"])
def test_json_output_stays_valid_json_when_piped(piped, name):
    d, _, as_json = piped
    code, out = as_json[name]
    assert code == 0, out
    record = json.loads(out)
    if name in ("compile", "emulate", "train"):
        assert str(d) in json.dumps(record)


def test_a_terminal_still_gets_wrapped_and_fitted_output(monkeypatch):
    """On a terminal the console keeps rich's behaviour: lines wrapped at the terminal's width."""
    from snncc.cli.output import WholeLines

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setenv("COLUMNS", "60")
    screen = Terminal()
    WholeLines(file=screen, highlight=False, force_terminal=True, color_system=None).print("word " * 40)
    assert max(len(line) for line in screen.getvalue().splitlines()) <= 60
    piped = io.StringIO()
    WholeLines(file=piped, highlight=False).print("word " * 40)
    assert len(piped.getvalue().splitlines()) == 1
