"""Messages a user reads: the Python API's spelling of options, dt suggestions, true counts, no
internal tracker numbers and no citations of files the repository does not have."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.spelling import python_spelling
from snncc_test_helpers import run_cli

ROOT = Path(__file__).resolve().parents[2]
NIR = ROOT / "tests" / "data" / "nir"


@pytest.mark.parametrize("line, python", [
    ("x.nir: dt: cannot infer dt; pass --dt", "x.nir: dt: cannot infer dt; pass dt="),
    ("m.pt: --time-steps: must be >= 1", "m.pt: time_steps: must be >= 1"),
    ("try --dt=0.001 or --reset=subtract", "try dt=0.001 or reset='subtract'"),
    ("re-encode or pass --set time_bin_size=4", "re-encode or pass overrides=['time_bin_size=4']"),
    ("--range tau_mem=0.01:0.1: bounds must be numbers", "ranges=['tau_mem=0.01:0.1']: bounds must be numbers"),
    ("-o does not say which target: pass --target (ir, loihi)", "output= does not say which target: pass target= (ir, loihi)"),
    ("give --bin in ms, --from raw", "give bin_ms= in ms, prefer= raw"),
    ("a-b --c-d x--y", "a-b c_d= x--y"),
])
def test_python_spelling_of_command_line_options(line, python):
    assert python_spelling(line) == python


def test_api_errors_name_keyword_arguments_and_the_cli_names_options(capsys):
    import snncc.api

    with pytest.raises(SnnccError) as caught:
        snncc.api.inspect(NIR / "two_lif_neurons.nir")
    err = caught.value
    assert "--dt" in err.line() and "--dt" not in str(err)
    assert "try dt=0.001" in str(err)
    code, _, stderr = run_cli(["inspect", NIR / "two_lif_neurons.nir"], capsys)
    assert code == 2 and "try --dt=0.001" in stderr and "dt=0.001 (" not in stderr.replace("--dt=0.001", "")
    with pytest.raises(SnnccError) as caught:
        snncc.api.compile(NIR / "two_lif_neurons.nir", output="out", dt=1e-3)
    assert "pass target=" in str(caught.value) and "pass --target" in caught.value.line()


def test_inspect_without_dt_suggests_one_from_the_time_constants(capsys):
    """two_lif_neurons.nir: tau 10 ms, r = 1 (Norse): dt = 1 ms makes the time constant 10 steps, and the
    suggested value works."""
    code, _, err = run_cli(["inspect", NIR / "two_lif_neurons.nir"], capsys)
    assert code == 2
    assert "the shortest time constant is 0.01 s: try --dt=0.001 (it spans 10 steps" in err
    assert not err.rstrip().endswith("pass --dt")
    code, out, err = run_cli(["inspect", NIR / "two_lif_neurons.nir", "--dt=0.001"], capsys)
    assert code == 0, err


def test_dt_suggestion_rounds_down_to_1_2_5_and_mentions_snntorchs_step():
    from snncc.frontends.nir import dt_suggestion

    assert "try --dt=0.002 " in dt_suggestion([np.array([0.025])], [np.array([1.0])])
    assert "try --dt=0.0005 " in dt_suggestion([np.array([0.006, 0.06])], [np.array([1.0])])
    text = dt_suggestion([np.array([0.06]), np.array([0.05])], [np.array([1e-4]), np.array([2e-4])])
    assert "--dt=0.0001 (snnTorch's export step)" in text
    assert "pass --dt (the step the graph was trained at)" == dt_suggestion([], [])


def test_loihi_report_counts_the_synapse_formats_it_uses():
    from snncc.targets.loihi.bundle.write import netx_compat
    from tests.loihi.helpers import random_network

    net = random_network(3, split_exponents=True)
    hidden = net.layers[1]
    hidden.wgt_exp = np.arange(hidden.weight.size).reshape(hidden.weight.shape) % 10 - 4   # ten exponents
    notes = [n for n in netx_compat(net) if "/layer/1/neuron/wgtExp:" in n]
    assert len(notes) == 1 and "10 synapse formats, one per exponent" in notes[0] and "two" not in notes[0]
    rec = [n for n in netx_compat(net) if "/layer/1/neuron/wgtExpRec:" in n]
    assert len(rec) == 1 and "2 synapse formats, one per exponent" in rec[0]


def _help_texts() -> list[tuple[str, str]]:
    import typer

    from snncc.cli.main import build_app

    def walk(cmd, path):
        yield path, cmd
        for name, sub in getattr(cmd, "commands", {}).items():
            yield from walk(sub, path + [name])

    root = typer.main.get_command(build_app())
    texts = []
    for path, cmd in walk(root, []):
        parts = [cmd.help or ""] + [getattr(p, "help", None) or "" for p in cmd.params]
        texts.append((" ".join(path) or "snncc", "\n".join(parts)))
    return texts


TRACKER = re.compile(r"\b(issue|stop) #?\d+", re.IGNORECASE)


def test_help_texts_name_no_internal_tracker_numbers():
    bad = [(cmd, m.group(0)) for cmd, text in _help_texts() for m in TRACKER.finditer(text)]
    assert bad == []


def _shipped_text_files():
    for root in ("snncc", "targets", "docs", "examples", "bench"):
        for path in sorted((ROOT / root).rglob("*")):
            if path.suffix in (".py", ".md", ".sh", ".txt") and "__pycache__" not in path.parts:
                yield path
    yield ROOT / "README.md"


def test_shipped_code_and_docs_name_no_internal_tracker_numbers():
    bad = [f"{p.relative_to(ROOT)}: {m.group(0)}" for p in _shipped_text_files()
           for m in TRACKER.finditer(p.read_text(encoding="utf-8"))]
    assert bad == []


SPEC_FILE = re.compile(r"(?<![\w/.-])(loihi|braille|ir|quality|jetson|xylo)\.md\b"     # a spec file, not docs/NAME.md
                       r"|\bthe spec('s)?\b|\bthe specification\b|\bspec (table|section)s?\b"
                       r"|\(spec:? [a-z_]+\.md")                                     # "(spec loihi.md", "(spec: braille.md"


def test_comments_cite_the_repositorys_docs_not_spec_files_it_lacks():
    """What the code relies on from the project's specification is in docs/ (cited as docs/NAME.md)."""
    bad = []
    for path in _shipped_text_files():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if SPEC_FILE.search(line):
                bad.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert bad == []
    for cited in re.findall(r"docs/([a-z_]+\.md)", "\n".join(p.read_text(encoding="utf-8")
                                                            for p in _shipped_text_files())):
        assert (ROOT / "docs" / cited).is_file(), cited


def test_no_text_says_the_ir_has_no_convolutions():
    from snncc.ir.nodes import Conv  # noqa: F401  (the IR defines convolutions)

    bad = [str(p.relative_to(ROOT)) for p in _shipped_text_files()
           if re.search(r"IR has no convolution", p.read_text(encoding="utf-8"), re.IGNORECASE)]
    assert bad == []
