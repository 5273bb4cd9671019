"""Real NIR graphs written by other frameworks (tests/data/nir, NIR paper artefacts): each compiles
for Loihi and Jetson or is refused with one line naming the reason; the trained Braille graphs keep
the float graph's decisions on Loihi (bit-exact emulation) at a reduced size.

Inputs are seeded random spike trains (SYNTHETIC): the figures are agreement with the float graph,
not accuracy on Braille recordings.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from nir_graphs import run_cli
from snncc.errors import SnnccError
from snncc.frontends import LoadOptions, load_model
from snncc.frontends.nir_legacy import normalise

DATA = Path(__file__).resolve().parents[1] / "data" / "nir"
GRAPHS = ["braille_zero_2023.nir", "braille_noDelay_noBias_subtract.nir", "braille_subgraph_2023.nir",
          "lif_norse.nir", "lif_rockpool.nir", "two_lif_neurons.nir"]


def _extra(name):
    return ["--reset", "subtract", "--allow-reset-change"] if "subtract" in name else []


@pytest.mark.parametrize("name", GRAPHS)
def test_real_graph_compiles_for_loihi_and_jetson(name, tmp_path, capsys):
    for target, out, extra in (("loihi", tmp_path / "g.net", _extra(name)),
                               ("jetson", tmp_path / "j", ["--time-steps", "20"] + _extra(name)[:2])):
        code, stdout, err = run_cli(["compile", DATA / name, "--dt", "1e-4", "--target", target, "-o", out, *extra],
                                    capsys)
        if code == 0:
            assert out.exists(), (target, stdout)
            if target == "loihi" and name.startswith("braille_zero"):   # auto measured every candidate
                assert "scale candidates, measured spike-count error" in stdout and "fine 0." in stdout, stdout
        else:   # refused: one line naming the reason, nothing written
            assert code == 2 and not out.exists(), (target, err)
            lines = [ln for ln in err.splitlines() if ln.startswith("snncc: error:")]
            assert len(lines) == 1 and "Traceback" not in err, err
    # every one of these graphs compiles for both targets today, except the legacy sub-graph (refused: it
    # lacks its input gains, see test_legacy_subgraph.py)
    if name == "braille_subgraph_2023.nir":
        assert code == 2 and "node 'hidden.lif'.w_in" in err, err
    else:
        assert code == 0, err


def test_older_nir_input_feeding_disagreeing_sizes_is_one_line():
    sub = {"type": "NIRGraph", "edges": [(b"input", b"a"), (b"input", b"b")],
           "nodes": {"input": {"type": b"Input", "shape": np.array([12])},
                     "a": {"type": b"Affine", "weight": np.zeros((3, 5)), "bias": np.zeros(3)},
                     "b": {"type": b"CubaLIF", "tau_mem": np.ones(7), "tau_syn": np.ones(7), "r": np.ones(7),
                           "v_leak": np.zeros(7), "v_threshold": np.ones(7)}}}
    top = {"type": "NIRGraph", "edges": [], "nodes": {"sub": sub}}
    with pytest.raises(SnnccError, match="undecidable"):
        normalise(top, "", [], "x.nir")


def test_damaged_nir_file_is_still_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.nir"
    bad.write_bytes(b"not hdf5")
    code, _, err = run_cli(["inspect", bad, "--dt", "1e-4"], capsys)
    assert code == 2 and err.strip().splitlines()[-1].startswith("snncc: error:") and "Traceback" not in err
