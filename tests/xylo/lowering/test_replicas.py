"""``--replicas K`` on Xylo: K copies of the hidden network, each fitted and rounded on its own calibration inputs,
the output neurons reading every copy with 1/K of the weights. The spec runs unchanged in XyloSim, the copies are
independent blocks (no fan-out grows), they differ, their errors partly average out, fine-tuning trains them, and
every refusal is one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.ir.serialize import save_graph
from snncc.ir.simulate import simulate
from snncc.targets.xylo import feed
from snncc.targets.xylo.emulation.emulator import emulate
from xylo_models import lower_with
from snncc.targets.xylo.spec import XyloSpec
from snncc_test_helpers import run_cli
from tests.xylo.oracle import XyloSimOracle

from xylo_models import chain, run_xylosim, spikes

QUICK = {"calibration_samples": 32, "time_steps": 80, "density": 0.15}


@pytest.fixture(scope="module")
def model():
    return chain(np.random.default_rng(5), n_in=6, n_hidden=12, n_out=3, beta=0.85, alpha_o=0.45, beta_o=0.7)


@pytest.fixture(scope="module")
def replicated(model):
    return lower_with(model, dict(QUICK, rule="relayed", replicas=3))


def test_replicas_are_independent_blocks_that_differ(replicated):
    low = replicated
    spec = low.spec
    rec = low.record()
    assert low.rule.endswith(", 3 replicas")
    hidden = next(p for p in low.populations if p.role == "hidden")
    assert hidden.copies == 3 and hidden.neurons == (0, 36) and rec["populations"][0]["copies"] == 3
    blocks = hidden.copy_neurons()
    assert blocks.shape == (3, 12)
    relays = [p for p in low.populations if p.role == "relay"]
    assert [p.name for p in relays] == ["relay of input#0", "relay of hidden#0", "relay of input#1",
                                        "relay of hidden#1", "relay of input#2", "relay of hidden#2"]
    # each copy's neurons and relays form a block: nothing crosses between copies
    copy_of = np.full(spec["threshold"].size, -1)
    for k in range(3):
        copy_of[blocks[k]] = k
    for r in relays:
        copy_of[r.neurons[0]:r.neurons[1]] = int(r.name[-1])
    assert (copy_of >= 0).all()
    pre, post, _ = np.nonzero(spec["weights_rec"])
    assert np.array_equal(copy_of[pre], copy_of[post])
    # every copy reaches the output neurons; the copies' weights differ (own inputs, own relay quantization)
    w_out = spec["weights_out"].astype(int)
    assert all(np.abs(w_out[blocks[k]]).sum() > 0 for k in range(3))
    w_in = spec["weights_in"].astype(int)
    assert not np.array_equal(w_in[:, blocks[0]], w_in[:, blocks[1]])
    thetas = [spec["threshold"][r.neurons[0]] for r in relays[::2]]
    assert thetas[0] < thetas[1] < thetas[2]                    # relays of copy k a step coarser


def test_replicas_of_given_calibration_inputs_fit_on_resamples_of_them(model):
    x = spikes(np.random.default_rng(9), 24, 80, 6, 0.15)
    low = lower_with(model, {"rule": "single-identified", "calibration": x, "replicas": 2})
    blocks = next(p for p in low.populations if p.role == "hidden").copy_neurons()
    w_in = low.spec["weights_in"].astype(int)
    assert not np.array_equal(w_in[:, blocks[0]], w_in[:, blocks[1]])
    cal = low.record()["calibration"]
    assert cal["replicas"] == 2 and "seeded resample" in cal["replica_inputs"]


def test_a_replicated_spec_runs_unchanged_in_xylosim(replicated):
    low = replicated
    x = spikes(np.random.default_rng(11), 24, 80, 6, 0.15)
    chip_x = low.chip_input(x)
    vendor = run_xylosim(low.spec, chip_x, record=True)
    mine = emulate(XyloSpec(**low.spec), chip_x, record=True)
    assert np.array_equal(vendor.output_spikes, mine.output_spikes) and vendor.output_spikes.sum() > 30
    assert np.array_equal(vendor.spikes, mine.spikes) and np.array_equal(vendor.vmem, mine.vmem)


def test_replicas_average_out_rounding_error(model):
    """Held-out output counts follow the float graph more closely with 4 copies than with one (same rule and
    calibration seed; deterministic)."""
    x = spikes(np.random.default_rng(3), 200, 80, 6, 0.15)
    ref = np.asarray(simulate(model, x, record="spikes").spikes["out"]).sum(axis=1)
    err = {}
    for k in (1, 4):
        low = lower_with(model, dict(QUICK, rule="relayed", replicas=k))
        counts = low.read_output(emulate(low.xylo_spec, low.chip_input(x)).output_spikes, x.shape[1]).sum(axis=1)
        err[k] = float(np.mean((counts - ref) ** 2))
    assert err[4] < 0.8 * err[1], err


def test_one_replica_is_the_plain_lowering(model):
    plain = lower_with(model, dict(QUICK, rule="relayed"))
    one = lower_with(model, dict(QUICK, rule="relayed", replicas=1))
    assert plain.rule == one.rule and all(np.array_equal(np.asarray(plain.spec[k]), np.asarray(one.spec[k]))
                                          for k in plain.spec if k != "aliases")


def test_the_student_reads_a_replicated_population_as_its_copies_mean(replicated):
    import torch

    from snncc.targets.xylo.finetune.tuning import lowered_student

    low = replicated
    student = lowered_student(low, 80)
    x = spikes(np.random.default_rng(4), 4, 80, 6, 0.15)
    with torch.no_grad():
        run = student(torch.as_tensor(x, dtype=torch.float64))
        full = student.core(student.chip_input(torch.as_tensor(x, dtype=torch.float64)), record=True)
    blocks = next(p for p in low.populations if p.role == "hidden").copy_neurons()
    shift = low.timing.shifts["hidden"]
    each = full.states["spikes"][:, shift:shift + 80][:, :, torch.as_tensor(blocks)]
    assert run.spikes["hidden"].shape == (4, 80, 12)
    assert torch.allclose(run.spikes["hidden"], each.mean(2))
    mine = emulate(student.export(), low.chip_input(x), record=True)
    assert np.array_equal(full.states["spikes"].numpy(), mine.spikes)


def test_too_many_replicas_for_the_chip_are_refused_in_one_line(tmp_path, capsys):
    big = chain(np.random.default_rng(1), n_in=16, n_hidden=60, n_out=3)     # relayed: 60 + 16 + 60 neurons a copy
    with pytest.raises(SnnccError, match=r"8 replicas need 1,088 hidden neurons \(136 each\); Xylo Audio 2 has "
                                         r"1,000") as err:
        lower_with(big, dict(QUICK, calibration_samples=8, time_steps=20, rule="relayed", replicas=8))
    assert err.value.field == "--replicas"
    path = tmp_path / "big.snnir"
    save_graph(big, path)
    out = tmp_path / "big.xylo"
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--rule", "relayed", "--replicas", "8",
                            "--calibration-samples", "8", "--time-steps", "20", "-o", out], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--replicas: 8 replicas need 1,088" in err and not out.exists()


@pytest.mark.parametrize("value,rule", [("0", "from 1 to 8"), ("9", "from 1 to 8"), ("two", "valid integer")])
def test_bad_replicas_are_refused_in_one_line(tmp_path, capsys, model, value, rule):
    path = tmp_path / "chain.snnir"
    save_graph(model, path)
    out = tmp_path / "x.xylo"
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--replicas", value, "-o", out], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--replicas" in err and rule in err and not out.exists()


def test_compile_finetunes_a_replicated_spec(tmp_path, capsys, model):
    """--replicas with --finetune through the command line: the manifest records both, XyloSim runs the written
    spec.npz with snncc's output spikes."""
    path = tmp_path / "chain.snnir"
    save_graph(model, path)
    out = tmp_path / "rep.xylo"
    code, _, err = run_cli(["compile", path, "--target", "xylo", "--rule", "relayed", "--replicas", "2",
                            "--calibration-samples", "12", "--time-steps", "40", "--finetune", "--finetune-samples",
                            "32", "--finetune-epochs", "1", "--density", "0.2", "-o", out], capsys)
    assert code == 0, err
    m = json.loads((out / "manifest.json").read_text())
    assert m["quantization"]["rule"].endswith(", 2 replicas")
    assert m["finetune"]["finetuned"] is True
    assert "equals the differentiable forward pass" in m["validation"]["finetune"]
    from snncc.targets.xylo.artefact.read import read_artefact

    written = read_artefact(out)
    x = spikes(np.random.default_rng(8), 8, 40, 6, 0.2)
    chip_x = feed.chip_window(x, written.input_pad, written.output_lag)
    vendor = XyloSimOracle(written.spec).run(chip_x)
    assert np.array_equal(vendor.output_spikes, emulate(written.spec, chip_x).output_spikes)
    # check measures the written replicated spec like any artefact
    code, out_text, err = run_cli(["check", path, "--artefact", out, "--samples", "30", "--json"], capsys)
    assert code == 0, err
    d = json.loads(out_text)
    assert d["artefact"]["target"] == "xylo" and not d["artefact"]["compiled_by_check"]
    assert d["stages"][-1]["key"] == "chip"


def _two_layers(rng):
    """input -> LIF (self loop, voltage bias) -> LIF -> readout (output current bias): two hidden populations, the
    always-on bias source shared by the replicas."""
    from snncc.ir import LIF, Dense, Graph, Input, Output, Readout, validate

    dt = 1e-3
    g = Graph(dt, name="two")
    g.add("input", Input(5))
    g.add("w1", Dense(rng.normal(0.2, 0.6, (8, 5))))
    g.add("h1", LIF(8, dt / 0.25, dt / 0.15, 1.0, reset="subtract", discretisation="euler",
                    bias=np.linspace(-0.02, 0.05, 8), bias_placement="voltage"))
    g.add("r1", Dense(rng.normal(0, 0.3, (8, 8))))
    g.add("w2", Dense(rng.normal(0.2, 0.7, (6, 8))))
    g.add("h2", LIF(6, dt / 0.25, dt / 0.125, 1.0, reset="subtract", discretisation="euler"))
    g.add("w3", Dense(rng.normal(0.1, 0.8, (3, 6)), bias=np.array([0.1, 0.0, 0.2])))
    g.add("out", LIF(3, dt / 0.5, dt / 0.25, 1.0, reset="subtract", discretisation="euler"))
    g.add("readout", Readout(3))
    g.add("output", Output(3))
    for a, b, d in [("input", "w1", 0), ("w1", "h1", 0), ("h1", "r1", 1), ("r1", "h1", 0), ("h1", "w2", 0),
                    ("w2", "h2", 0), ("h2", "w3", 0), ("w3", "out", 0), ("out", "readout", 0),
                    ("readout", "output", 0)]:
        g.connect(a, b, delay=d)
    return validate(g)


@pytest.mark.parametrize("rule", ["single-identified", "relayed"])
def test_replicas_of_two_hidden_layers_with_biases(rule):
    g = _two_layers(np.random.default_rng(2))
    plain = lower_with(g, dict(QUICK, rule=rule))
    low = lower_with(g, dict(QUICK, rule=rule, replicas=3))
    hidden = [p for p in low.populations if p.role == "hidden"]
    assert [(p.name, p.copies, p.neurons) for p in hidden] == [("h1", 3, (0, 24)), ("h2", 3, (24, 42))]
    n_plain, n = plain.spec["threshold"].size, low.spec["threshold"].size
    assert n - 1 == 3 * (n_plain - 1)                        # one shared bias source, the last hidden neuron
    assert low.spec["bias"][n - 1] == low.spec["threshold"][n - 1]
    assert any(f"hidden neuron {n - 1} is the always-on bias source" in note for note in hidden[1].notes)
    h1, h2 = hidden[0].copy_neurons(), hidden[1].copy_neurons()
    w_rec = low.spec["weights_rec"]
    for k in range(3):                                      # copy k of h2 reads copy k of h1 only
        others = np.setdiff1d(h1, h1[k])
        assert np.abs(w_rec[h1[k]][:, h2[k]]).sum() > 0 and not np.any(w_rec[others][:, h2[k]])
    x = spikes(np.random.default_rng(6), 16, 80, 5, 0.2)
    chip_x = low.chip_input(x)
    vendor = run_xylosim(low.spec, chip_x, record=True)
    mine = emulate(XyloSpec(**low.spec), chip_x, record=True)
    assert np.array_equal(vendor.output_spikes, mine.output_spikes) and np.array_equal(vendor.spikes, mine.spikes)
    assert vendor.output_spikes.sum() > 20 and vendor.spikes[:, :, h2.ravel()].sum() > 20


@pytest.mark.parametrize("value", [0, 9])
def test_the_library_refuses_bad_replicas_before_any_work(model, value):
    with pytest.raises(SnnccError, match="replicas must be a whole number from 1 to 8") as err:
        lower_with(model, dict(QUICK, replicas=value, calibration_samples=10**9))   # never drawn: refused first
    assert err.value.field == "--replicas"
