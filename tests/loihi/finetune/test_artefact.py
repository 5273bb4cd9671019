"""``snncc compile --finetune`` (and ``snncc.api.compile(finetune=True)``): the capability of the target
interface, its declared options, the artefact's record, ``--finetune-out`` and the one-line refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir.serialize import save_graph
from snncc_test_helpers import run_cli
from tests.finetune.test_engine import tiny_graph

TINY = {"time_steps": 32, "finetune_samples": 48, "finetune_epochs": 1, "density": 0.25, "scale": "per-layer",
        "allow_reset_change": True}


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("ft") / "tiny.snnir"
    save_graph(tiny_graph(), path)
    return path


@pytest.fixture(scope="module")
def tuned(model):
    """One fine-tuned compile through the API (module-scoped: every test below reads it)."""
    from snncc import api

    before = model.read_bytes()
    out = model.parent / "tuned.net"
    phases: list[str] = []
    record = api.compile(model, output=out, target="loihi", finetune=True, finetune_out=str(model.parent / "a.nir"),
                         progress=lambda done, total, phase: phases.append(phase), **TINY)
    return record, out, phases, before


def test_the_artefact_records_its_finetuning(tuned):
    record, out, phases, _ = tuned
    summary = record.as_dict()
    json.dumps(summary, default=float)
    ft = summary["finetune"]
    assert ft["finetuned"] and ft["seed"] == 0 and ft["steps"] == 1      # 48 samples in batches of 64, 1 epoch
    assert ft["inputs"]["held_out"] == 256 and ft["inputs"]["source"] == "synthetic"    # the floor for 48 samples
    for key in ("agreement_before", "agreement_after"):
        a = ft[key]
        assert a["samples"] == 256 and a["low"] <= a["share"] <= a["high"]
    assert {"teacher", "training", "evaluating"} <= set(phases)
    # the bundle holds the same record, and the emulator runs it (bit-exact reader and checks)
    import h5py

    with h5py.File(out, "r") as f:
        written = json.loads(f["snncc/finetune"][0].decode())
        meta = json.loads(f["snncc/metadata"][0].decode())
    assert written["agreement_after"] == ft["agreement_after"] and meta["finetune"]["finetuned"]


def test_finetune_out_is_the_adapted_float_graph_and_the_model_is_untouched(tuned, model):
    from snncc.frontends import LoadOptions, load_model

    record, _, _, before = tuned
    assert model.read_bytes() == before
    adapted = load_model(Path(record.finetune_out), LoadOptions())
    from snncc.ir.nodes import LIF

    names = adapted.of_kind(LIF)
    assert len(names) == 2 and all(adapted.node(n).reset == "zero" for n in names)   # the deployed reset


def test_offered_once_by_the_targets_that_have_the_capability():
    from snncc.targets import offered_options, offering

    assert offering("finetune") == ["c", "loihi", "xylo"]
    offers = {o.name: o for o in offered_options(["lower", "finetune"])}
    for name in ("finetune", "finetune_out", "data", "density", "device"):
        assert offers[name].targets == ("c", "loihi", "xylo")
    assert offers["finetune_out"].path == "output" and offers["data"].path == "input"
    assert "finetune" not in {o.name for o in offered_options(["lower"])}


@pytest.mark.parametrize("given,field,words", [
    ({"density": 0.2}, "--density", "applies only to fine-tuning"),
    ({"finetune_out": "x.nir"}, "--finetune-out", "applies only to fine-tuning"),
    ({"finetune": True, "device": "tpu"}, "--device", "not a device"),
    ({"finetune": True, "device": "cuda"}, "--device", "CUDA"),
    ({"finetune": True, "density": 1.5}, "--density", "(0, 1]"),
    ({"finetune": True, "density": 0.1, "data": "missing.npz"}, "--density", "not with"),
    ({"finetune": True, "data": "missing.npz"}, "--data", "does not exist"),
])
def test_refusals_are_one_line(model, tmp_path, given, field, words):
    import torch

    from snncc import api

    if given.get("device") == "cuda" and torch.cuda.is_available():
        pytest.skip("a CUDA device is present")
    with pytest.raises(SnnccError) as e:
        api.compile(model, output=tmp_path / "x.net", **given)
    assert e.value.field == field and words in str(e.value) and "\n" not in str(e.value)
    assert not (tmp_path / "x.net").exists()


def test_finetune_out_never_overwrites_the_model(model, tmp_path):
    from snncc import api

    before = model.read_bytes()
    with pytest.raises(SnnccError) as e:
        api.compile(model, output=tmp_path / "x.net", finetune=True, finetune_out=str(model), **TINY)
    assert e.value.field == "--finetune-out" and model.read_bytes() == before
    data = tmp_path / "inputs.npz"
    np.savez(data, inputs=np.zeros((4, 32, 6), np.uint8))
    kept = data.read_bytes()
    with pytest.raises(SnnccError) as e:
        api.compile(model, output=tmp_path / "x.net", finetune=True, data=str(data), finetune_out=str(data), **TINY)
    assert e.value.field == "--finetune-out" and data.read_bytes() == kept
    with pytest.raises(SnnccError) as e:
        api.compile(model, output=tmp_path / "x.net", finetune=True, finetune_out=str(tmp_path / "x.net"), **TINY)
    assert e.value.field == "--finetune-out"


def test_a_target_without_the_capability_refuses_in_one_line(model, tmp_path, capsys):
    code, out, err = run_cli(["compile", model, "--target", "ir", "-o", tmp_path / "x.snnir", "--finetune"], capsys)
    assert code == 2 and err.count("\n") == 1
    assert "--finetune: target 'ir' has no fine-tuning" in err and "--target loihi" in err
    assert not (tmp_path / "x.snnir").exists()


def test_cli_flags_and_declared_paths(model, tmp_path, capsys):
    """--data is an input path of compile (protected: --finetune-out may not replace it)."""
    data = tmp_path / "inputs.npz"
    np.savez(data, inputs=(np.random.default_rng(0).random((40, 32, 6)) < 0.25).astype(np.uint8))
    code, out, err = run_cli(["compile", model, "-o", tmp_path / "x.net", "--scale", "per-layer",
                              "--allow-reset-change", "--finetune", "--data", data, "--finetune-out", data], capsys)
    assert code == 2 and "--finetune-out: is an input" in err and err.count("\n") == 1
    assert np.load(data)["inputs"].shape == (40, 32, 6)
    # the flag's input declaration protects it like the command's own inputs: -o may not replace it either
    code, out, err = run_cli(["compile", model, "--target", "loihi", "-o", data, "--scale", "per-layer",
                              "--allow-reset-change", "--finetune", "--data", data], capsys)
    assert code == 2 and "is an input of this command" in err and err.count("\n") == 1
    assert np.load(data)["inputs"].shape == (40, 32, 6)
    from snncc.cli.main import build_app
    import typer

    from snncc.cli.paths import declaration_of

    command = typer.main.get_command(build_app()).commands["compile"]
    declared = declaration_of(command.callback)
    assert "data" in declared.inputs and "finetune_out" in declared.outputs


def test_given_data_is_split_and_recorded(model, tmp_path):
    from snncc import api

    data = tmp_path / "inputs.npz"
    np.savez(data, inputs=(np.random.default_rng(0).random((40, 32, 6)) < 0.25).astype(np.uint8))
    record = api.compile(model, output=tmp_path / "d.net", finetune=True, data=str(data), finetune_epochs=1,
                         scale="per-layer", allow_reset_change=True)
    inputs = record.as_dict()["finetune"]["inputs"]
    assert inputs["source"] == "data" and inputs["held_out"] == 10 and inputs["validation"] == 5
    assert inputs["train"] == 25 and inputs["steps"] == 32


def test_check_measures_the_finetuned_bundle_against_the_model_as_trained(tuned, model):
    """check --artefact runs the fine-tuned bundle again and compares it with the float model as trained (its
    own reset: subtract here), not with the reset-changed graph."""
    from snncc import api

    _, out, _, _ = tuned
    record = api.check(model, artefact=out, samples=20, density=0.25).as_dict()
    assert record["reference"] == "the float graph as trained (its own reset)"
    # its breakdown is given (stage (c): the fine-tuned registers in float), and the note names fine-tuning
    assert [s["cause"] for s in record["stages"]] == ["reset", "weights", "decays", "saturation"], record["stages"]
    assert all(record["causes"][c] is not None for c in ("reset", "weights", "decays", "saturation"))
    assert any("fine-tuned bundle (--finetune)" in n for n in record["notes"]), record["notes"]
    assert not any("another snncc version" in n for n in record["notes"])
    assert record["artefact"]["path"] == str(out)
