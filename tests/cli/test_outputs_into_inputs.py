"""No command writes into what it reads: an output inside an input directory artefact (a file of it, or a new one
beside its files) is refused in one line, and an output's suffix must say what is written (.npz, .png)."""

from __future__ import annotations

import numpy as np
import pytest

from snncc_test_helpers import run_cli


@pytest.fixture(scope="module")
def jetson_artefact(tmp_path_factory, shared_nir):
    from snncc.api import compile as compile_model

    d = tmp_path_factory.mktemp("into")
    compile_model(shared_nir / "braille_noDelay_noBias_subtract.nir", dt=1e-4, reset="subtract", target="jetson",
                  output=d / "j", time_steps=20)
    np.save(d / "in12.npy", (np.random.default_rng(0).random((2, 20, 12)) < 0.1).astype(np.uint8))
    return d


def _refused(args, capsys, field: str, rule: str) -> None:
    code, out, err = run_cli(args, capsys)
    (line,) = err.strip().splitlines()
    assert code == 2 and out == "" and f": {field}: " in line and rule in line, line


def test_outputs_inside_an_input_artefact_are_refused(jetson_artefact, capsys):
    d = jetson_artefact
    before = {p.name: p.read_bytes() for p in (d / "j").iterdir()}
    for out, rule in (("model.onnx", "is an input of this command"), ("new.npz", "lies inside an input of this command")):
        _refused(["run", d / "j", "-i", d / "in12.npy", "-o", d / "j" / out], capsys, "output", rule)
    assert {p.name: p.read_bytes() for p in (d / "j").iterdir()} == before


def test_an_output_named_for_another_format_is_refused(jetson_artefact, tmp_path, capsys, shared_nir):
    d = jetson_artefact
    _refused(["emulate", shared_nir / "braille_noDelay_noBias_subtract.nir", "--dt", "1e-4", "--reset", "subtract",
              "-i", d / "in12.npy", "-o", tmp_path / "e2.npy"], capsys, "--output", "name the file .npz")
    _refused(["map", shared_nir / "braille_zero_2023.nir", "--dt", "1e-4", "--plot", tmp_path / "plot.txt"], capsys,
             "--plot", "name the file .png")
    assert not list(tmp_path.iterdir())
