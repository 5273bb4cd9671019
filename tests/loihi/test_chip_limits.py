"""chip.py states Loihi 1's formats and limits once: changing one value there changes every user.

Each test moves one limit in ``chip`` and shows that the passes, the bundle reader and checker, the
resource model and the emulator's readable statement follow it (refusing what they accepted
before, or the reverse). The numba kernel and ``resources.LOIHI1`` take their values when built;
the last tests change a value before they are imported, in a fresh interpreter.
"""

from __future__ import annotations

import ast
import io
import json
import subprocess
import sys
import tokenize
from pathlib import Path

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.targets.loihi import chip
from snncc.targets.loihi.lowering import bias_sources
from snncc.targets.loihi.bundle.read import read_bundle
from snncc.targets.loihi.bundle.write import check_network, write_bundle
from snncc.targets.loihi.emulation.emulator import reference_run
from snncc.targets.loihi.network import LoihiLayer
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.lowering.quantize import decay_register, threshold_mantissa
from snncc.targets.loihi.mapping.resources import ChipSpec, check_delay
from snncc.targets.loihi.lowering.timing import lower_timing
from tests.loihi.helpers import random_network, small_graph

LOIHI_DIR = Path(chip.__file__).parent


def _delayed_graph(delay: int):
    """A chain whose input projection needs an extra synaptic delay of ``delay`` steps on Loihi."""
    graph = small_graph(order="loihi", seed=0, recurrent=False)
    graph.set_delay("input", "w_in", delay + 1)
    return graph


def _network(delay: int = 0, v_th_mant: int = 100, ref_delay: int = 1):
    net = random_network(3, recurrent=False, per_synapse_delays=False, bias=False)
    hidden = net.layers[1]
    hidden.delay, hidden.v_th_mant, hidden.ref_delay = delay, v_th_mant, ref_delay
    return net


def test_the_delay_limit_moves_the_timing_pass_bias_sources_bundle_and_resources_together(monkeypatch, tmp_path):
    path = tmp_path / "d5.net"
    write_bundle(_network(delay=5), path)                   # 62 allows 5 ...
    assert lower_timing(_delayed_graph(5))[1].projections[0].extra_delay == 5
    assert read_bundle(path).layers[1].delay == 5
    monkeypatch.setattr(chip, "MAX_EXTRA_DELAY", 4)         # ... 4 does not
    lower_timing(_delayed_graph(4))
    with pytest.raises(SnnccError, match="at most 4"):
        lower_timing(_delayed_graph(5))
    with pytest.raises(SnnccError, match=r"0\.\.4"):
        read_bundle(path)
    with pytest.raises(SnnccError, match=r"0\.\.4"):
        check_network(_network(delay=5))
    check_network(_network(delay=4))
    assert ChipSpec().max_delay == 4
    assert check_delay("hidden", 5, ChipSpec()) and not check_delay("hidden", 4, ChipSpec())
    pre, post = LoihiLayer("input", "input", 3), _network().layers[1]
    with pytest.raises(SnnccError, match="at most 4"):     # a current bias from IR step 6 needs delay 5
        bias_sources.attach(pre, post, 0, [(6, np.full(post.n, 2, np.int16))])


def test_a_register_range_moves_the_quantizer_and_the_bundle_checks_together(monkeypatch, tmp_path):
    path = tmp_path / "th.net"
    write_bundle(_network(v_th_mant=150), path)
    assert threshold_mantissa(1.0, 150.0) == 150
    monkeypatch.setattr(chip, "V_TH_MANT_MAX", 120)
    with pytest.raises(SnnccError, match=r"1\.\.120"):
        threshold_mantissa(1.0, 150.0)
    with pytest.raises(SnnccError, match=r"1\.\.120"):
        read_bundle(path)
    with pytest.raises(SnnccError, match=r"1\.\.120"):
        check_network(_network(v_th_mant=150))
    assert threshold_mantissa(1.0, 120.0) == 120


def test_the_refractory_limit_moves_the_timing_pass_and_the_bundle_checks(monkeypatch, tmp_path):
    path = tmp_path / "ref.net"
    write_bundle(_network(ref_delay=3), path)
    graph = small_graph(order="spytorch", seed=0)           # the paper's order: refractory 2
    assert lower_timing(graph)[1].ref_delay["hidden"] == 2
    monkeypatch.setattr(chip, "REF_DELAY_MAX", 1)
    with pytest.raises(SnnccError, match="refractory period of 2 steps"):
        lower_timing(graph)
    with pytest.raises(SnnccError, match=r"1\.\.1"):
        read_bundle(path)
    with pytest.raises(SnnccError, match="refDelay"):
        check_network(_network(ref_delay=3))


def test_the_decay_register_range_moves_the_quantizer_and_the_bundle_checks(monkeypatch):
    assert decay_register(0.005, 0.006) == 2315               # the paper's iDecay (spec loihi.md)
    net = _network()
    net.layers[1].i_decay = 4096
    check_network(net)
    monkeypatch.setattr(chip, "DECAY_ONE", 2048)
    assert decay_register(0.005, 0.006) == 1157               # int(2048 * (1 - exp(-5/6)))
    with pytest.raises(SnnccError, match=r"0\.\.2048"):
        check_network(net)


def test_core_limits_move_the_resource_model_and_the_mapper(monkeypatch):
    net = random_network(0, recurrent=False, bias=False)      # 11 hidden + 5 output neurons
    assert map_network(net, ChipSpec()).n_cores == 1
    monkeypatch.setattr(chip, "COMPARTMENTS_PER_CORE", 4)
    spec = ChipSpec()
    assert spec.limits()["neurons"] == 4
    cmap = map_network(net, spec)
    assert cmap.n_cores >= 5 and all(core.usage.neurons <= 4 for core in cmap.cores)


def test_state_widths_move_the_emulators_readable_statement(monkeypatch):
    """The readable path (reference_run) reads the widths at call time; the numba kernel freezes
    them when it is compiled (see the fresh-interpreter test below)."""
    net = random_network(1, bias=False)
    x = (np.random.default_rng(0).random((2, 30, net.input_width)) < 0.3).astype(np.uint8)
    assert reference_run(net, x).overflow["u_wrap"] == 0
    monkeypatch.setattr(chip, "U_BITS", 6)
    assert reference_run(net, x).overflow["u_wrap"] > 0
    monkeypatch.setattr(chip, "V_MAX", 1000)
    monkeypatch.setattr(chip, "V_MIN", -1000)
    assert (LoihiLayer("l", "dense", 1).vmin, LoihiLayer("l", "dense", 1).vmax) == (-1000, 1000)


PROBE = """
import json
import snncc.targets.loihi.chip as chip
chip.COMPARTMENTS_PER_CORE = 4      # the one-line change, made before any user is imported
chip.Q_BITS = 9
from snncc.targets.loihi.emulation import flat as _kernel
from snncc.targets.loihi.mapping import fanin
from snncc.targets.loihi.mapping.partition import map_network
from snncc.targets.loihi.mapping.resources import LOIHI1
from tests.loihi.helpers import random_network
cmap = map_network(random_network(0, recurrent=False, bias=False))
print(json.dumps({"loihi1": LOIHI1.compartments_per_core, "q_half": _kernel.Q_HALF,
                  "cores": cmap.n_cores, "most": max(c.usage.neurons for c in cmap.cores)}))
"""


def test_a_value_changed_before_import_reaches_loihi1_the_default_map_and_the_kernel():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=300,
                         cwd=LOIHI_DIR.parent.parent)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["loihi1"] == 4 and got["q_half"] == 1 << 9
    assert got["cores"] >= 5 and got["most"] <= 4


def test_chip_imports_nothing_heavy():
    tree = ast.parse((LOIHI_DIR / "chip.py").read_text())
    imported = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    imported |= {node.module.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert imported <= {"__future__", "numpy"}


# numbers that are Loihi limits or formats: in code (not comments or docstrings) only chip.py may write them
CHIP_NUMBERS = {"62", "252", "254", "1024", "4095", "4096", "16384", "131071", "8388607"}
CHIP_POWERS = {("2", "**", "12"), ("2", "**", "17"), ("2", "**", "21"), ("2", "**", "23"),
               ("1", "<<", "12"), ("1", "<<", "21"), ("1", "<<", "23"), (">>", "12", None)}


def _literals(path: Path) -> list[str]:
    tokens = [t for t in tokenize.generate_tokens(io.StringIO(path.read_text()).readline)
              if t.type in (tokenize.NUMBER, tokenize.OP)]
    found = [f"{path.relative_to(LOIHI_DIR)}:{t.start[0]}: {t.string}" for t in tokens if t.type == tokenize.NUMBER and t.string in CHIP_NUMBERS]
    for a, b, c in zip(tokens, tokens[1:], tokens[2:] + [None]):
        triple = (a.string, b.string, c.string if c is not None else None)
        if triple in CHIP_POWERS:
            found.append(f"{path.relative_to(LOIHI_DIR)}:{a.start[0]}: {' '.join(triple)}")
        elif (a.string, b.string, None) in CHIP_POWERS:
            found.append(f"{path.relative_to(LOIHI_DIR)}:{a.start[0]}: {a.string} {b.string}")
    return found


def test_the_chip_numbers_are_written_only_in_chip_py():
    sources = [p for p in sorted(LOIHI_DIR.rglob("*.py")) if p.relative_to(LOIHI_DIR).as_posix() != "chip.py"]
    assert len(sources) > 30   # every sub-package is scanned
    assert [hit for p in sources for hit in _literals(p)] == []
