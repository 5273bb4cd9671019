"""A NIR graph whose inferred dt (snnTorch's r = tau/dt) equals a population's time constant would compile into a
neuron that keeps no state (beta = 1 - dt/tau = 0): refused in one line naming the population and the --dt to try,
as for the two-neuron graph with the same r = 1 pattern; with --dt given, the graph compiles."""

from __future__ import annotations

import pytest

from snncc_test_helpers import run_cli


@pytest.mark.parametrize("name, node, step", [("lif_norse.nir", "node '1'", "--dt=0.0002"),
                                               ("two_lif_neurons.nir", "node 'lif1'", "--dt=0.001")])
def test_an_inferred_dt_that_leaves_no_memory_is_refused(name, node, step, shared_nir, tmp_path, capsys):
    code, out, err = run_cli(["compile", shared_nir / name, "--target", "ir", "-o", tmp_path / "m.snnir"], capsys)
    (line,) = err.strip().splitlines()
    assert code == 2 and out == "" and not (tmp_path / "m.snnir").exists()
    assert line.startswith(f"snncc: error: {shared_nir / name}: {node}: cannot infer dt") and step in line, line
    assert "keep no state" in line
    code, _, err = run_cli(["compile", shared_nir / name, "--dt", step.split("=")[1], "--target", "ir", "-o",
                            tmp_path / "m.snnir"], capsys)
    assert code == 0, err
