"""``snncc compile --target xylo --finetune``: the Xylo target's ``finetune`` capability. The artefact directory is
every Xylo artefact's, its manifest records the fine-tuning, XyloSim runs the fine-tuned spec.npz with the output
spikes of snncc's emulator, the student works in the model's time, and the refusals are one line."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.ir.serialize import save_graph
from snncc.targets.xylo.spec import XyloSpec
from snncc_test_helpers import run_cli
from tests.finetune.test_engine import kept_by_the_rule
from tests.xylo.oracle import XyloSimOracle

from xylo_models import chain

QUICK = ["--calibration-samples", "12", "--time-steps", "40"]
TUNE = ["--finetune", "--finetune-samples", "48", "--finetune-epochs", "2", "--density", "0.25"]


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    path = tmp_path_factory.mktemp("xft") / "chain.snnir"
    save_graph(chain(np.random.default_rng(0), w_scale=1.0), path)     # output IR delay 0: the chip reads it 1 late
    return path


@pytest.fixture(scope="module")
def tuned(model):
    """One fine-tuned compile through the command line (module-scoped: the tests below read it)."""
    from snncc.cli.main import run

    before = model.read_bytes()
    out = model.parent / "tuned.xylo"
    js = model.parent / "compile.json"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = run(["compile", str(model), "--target", "xylo", "-o", str(out), *QUICK, *TUNE, "--json"])
    assert code == 0
    js.write_text(buf.getvalue())
    return out, json.loads(buf.getvalue()), before


def test_the_artefact_directory_records_its_finetuning(tuned, model):
    out, summary, before = tuned
    assert model.read_bytes() == before                       # the model file is never touched
    assert sorted(p.name for p in out.iterdir()) == ["README.md", "manifest.json", "run_on_board.py", "spec.npz"]
    m = json.loads((out / "manifest.json").read_text())
    ft = m["finetune"]
    assert ft["finetuned"] is True and ft["seed"] == 0
    assert ft["inputs"]["source"] == "synthetic" and ft["inputs"]["train"] == 48 and ft["inputs"]["steps"] == 40
    assert ft["inputs"]["density"] == 0.25
    assert m["feed"]["sample_steps"] == ft["inputs"]["steps"] == 40        # one time base: calibration and tuning
    assert ft["steps"] == 2 * 1 and ft["kept_epoch"] in (0, 1, 2)      # 48 samples = 1 batch of 64, 2 epochs
    for key in ("agreement_before", "agreement_after"):
        a = ft[key]
        assert 0 <= a["low"] <= a["share"] <= a["high"] <= 1 and a["samples"] == ft["inputs"]["held_out"]
    record = ft["record"]
    assert kept_by_the_rule(record["validation"], ft["kept_epoch"])
    assert "equals the differentiable forward pass" in m["validation"]["finetune"]
    assert m["validation"]["spec_file"].startswith("checked: spec.npz read back")
    for name, digest in m["files"].items():
        assert hashlib.sha256((out / name).read_bytes()).hexdigest() == digest
    assert summary["finetune"]["agreement_after"] == ft["agreement_after"]


def test_the_held_out_figure_is_the_written_spec_run_by_the_emulator(tuned, model):
    """The manifest's 'after' is re-measured here from spec.npz: the same seeded split, the float graph as trained."""
    from snncc.measure.agreement import argmax_agreement
    from snncc.finetune.inputs import split_inputs
    from snncc.finetune.teacher import run_teacher
    from snncc.frontends import load_model
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.feed import chip_window, read_window

    out, _, _ = tuned
    m = json.loads((out / "manifest.json").read_text())
    inp = m["finetune"]["inputs"]
    split = split_inputs(width=6, steps=40, density=0.25, train=inp["train"], validation=inp["validation"],
                         held_out=inp["held_out"], seed=0)
    graph = load_model(model)
    x = split.x[split.held_out]
    teacher = run_teacher(graph, x, ("hidden", "out"), voltage=False).counts
    pad, lag = m["feed"]["input_pad"], m["feed"]["output_lag"]
    spec = XyloSpec.load_npz(out / "spec.npz")
    counts = read_window(emulate(spec, chip_window(x, pad, lag)).output_spikes, lag, 40).sum(axis=1)
    assert argmax_agreement(teacher, counts).as_dict() == m["finetune"]["agreement_after"]


def test_xylosim_runs_the_finetuned_spec_with_the_output_spikes_of_snncc_emulate(tuned, tmp_path, capsys):
    out, _, _ = tuned
    x = (np.random.default_rng(7).random((4, 40, 6)) < 0.25).astype(np.uint8)
    np.save(tmp_path / "x.npy", x)
    res = tmp_path / "em.npz"
    code, _, err = run_cli(["emulate", out, "--input", tmp_path / "x.npy", "-o", res, "--record", "all"], capsys)
    assert code == 0, err
    m = json.loads((out / "manifest.json").read_text())
    pad, lag = m["feed"]["input_pad"], m["feed"]["output_lag"]
    assert lag == 1                                            # the chain's output runs one step late on the chip
    fed = np.zeros((4, 40 + max(pad, lag), 6), np.uint8)
    fed[:, pad:pad + 40] = x
    oracle = XyloSimOracle(XyloSpec.load_npz(out / "spec.npz")).run(fed, record=True)
    with np.load(res, allow_pickle=False) as got:
        assert got["output_spikes"].sum() > 0
        assert np.array_equal(got["output_spikes"], oracle.output_spikes[:, lag:lag + 40])
        for name in ("vmem", "isyn", "isyn2", "spikes", "vmem_out", "isyn_out"):
            assert np.array_equal(got[name], getattr(oracle, name)[:, lag:lag + 40]), name


def test_check_runs_the_finetuned_artefact(tuned, model):
    from snncc import api

    out, _, _ = tuned
    record = api.check(model, artefact=out, samples=20, density=0.25).as_dict()
    assert json.dumps(record, default=str)


def test_finetune_out_is_refused_in_one_line_before_any_work(model, tmp_path, capsys):
    code, _, err = run_cli(["compile", model, "--target", "xylo", "-o", tmp_path / "x.xylo", *QUICK, *TUNE,
                            "--finetune-out", tmp_path / "a.nir"], capsys)
    assert code == 2 and err.count("\n") == 1
    assert "--finetune-out: a fine-tuned Xylo spec has no faithful float NIR reading" in err and "spec.npz" in err
    assert not (tmp_path / "x.xylo").exists() and not (tmp_path / "a.nir").exists()


@pytest.mark.parametrize("flags,field,words", [
    (["--density", "0.2"], "--density", "applies only to fine-tuning"),
    (["--finetune", "--device", "tpu"], "--device", "not a device"),
    (["--finetune", "--density", "1.5"], "--density", "(0, 1]"),
    (["--finetune", "--data", "missing.npz"], "--data", "does not exist"),
])
def test_refusals_are_one_line(model, tmp_path, capsys, flags, field, words):
    code, _, err = run_cli(["compile", model, "--target", "xylo", "-o", tmp_path / "x.xylo", *QUICK, *flags], capsys)
    assert code == 2 and err.count("\n") == 1 and f"{field}: " in err and words in err, err
    assert not (tmp_path / "x.xylo").exists()


def test_offered_by_xylo_and_loihi():
    from snncc.targets import offered_options, offering

    assert offering("finetune") == ["c", "loihi", "xylo"]
    offers = {o.name: o for o in offered_options(["lower", "finetune"])}
    assert offers["finetune_out"].targets == ("c", "loihi", "xylo")


# -- the student in the model's time --------------------------------------------------------------------
@pytest.fixture(scope="module")
def lowered():
    from xylo_models import lower_with

    g = chain(np.random.default_rng(0), w_scale=1.0, bias=np.full(12, 0.05))
    return lower_with(g, {"rule": "single", "calibration_samples": 12, "time_steps": 40})


def test_the_student_in_model_time_equals_the_emulator_on_the_chip_window(lowered):
    from snncc.targets.xylo.finetune.tuning import forward_equals_emulator, lowered_counts, lowered_student

    student = lowered_student(lowered, 40)
    x = (np.random.default_rng(3).random((6, 40, 6)) < 0.3).astype(np.uint8)
    with torch.no_grad():
        run = student(torch.as_tensor(x))
    assert run.spikes["out"].shape == (6, 40, 3) and run.spikes["hidden"].shape == (6, 40, 12)
    counts = lowered_counts(lowered)(student, x)
    assert counts.sum() > 0 and np.array_equal(np.rint(run.counts.numpy()).astype(np.int64), counts)
    assert "equals" in forward_equals_emulator(student, x)
    # teacher forcing in the model's time: forcing the hidden population with its own free-running spikes changes
    # nothing; forcing it silent takes most of the output's drive away
    with torch.no_grad():
        own = student(torch.as_tensor(x), force={"hidden": run.spikes["hidden"]})
        silent = student(torch.as_tensor(x), force={"hidden": torch.zeros_like(run.spikes["hidden"])})
    assert torch.equal(own.counts, run.counts) and torch.equal(own.spikes["hidden"], run.spikes["hidden"])
    assert silent.counts.sum() < run.counts.sum()


def test_training_keeps_the_synapse_layout_and_the_neurons_that_carry_no_population(lowered):
    """``project`` restores zero weights and the bias source's registers, whatever the optimiser did."""
    from snncc.targets.xylo.finetune.tuning import lowered_student

    spec = lowered.xylo_spec
    student = lowered_student(lowered, 40)
    carried = np.zeros(spec.n_hidden, bool)
    carried[:12] = True
    assert spec.n_hidden > 12, "the chain with a bias has the always-on source neuron"
    with torch.no_grad():
        for p in student.parameters():
            p.add_(torch.randn_like(p) * 50.0)
    student.project()
    tuned = student.export()
    for name in ("weights_in", "weights_rec", "weights_out"):
        before, after = getattr(spec, name), getattr(tuned, name)
        assert np.all(after[before == 0] == 0), name
        assert np.any(after != before), name
    assert np.array_equal(tuned.threshold[~carried], spec.threshold[~carried])
    assert np.array_equal(tuned.bias[~carried], spec.bias[~carried])
    assert np.any(tuned.threshold[carried] != spec.threshold[carried])


def test_a_spec_the_student_cannot_hold_is_refused_in_one_line(lowered):
    import dataclasses

    from snncc.targets.xylo.finetune.student import ChipTimeStudent

    spec = lowered.xylo_spec
    aliased = dataclasses.replace(spec, aliases=[[1]] + [[] for _ in range(spec.n_hidden - 1)])
    with pytest.raises(SnnccError) as e:
        ChipTimeStudent(aliased, 40, {"hidden": np.arange(12)}, "out", input_pad=0, output_lag=1,
                        shifts={"hidden": 0})
    assert e.value.field == "aliases" and "\n" not in str(e.value)
