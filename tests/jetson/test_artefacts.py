"""Both artefacts of an RSNN, an FFSNN, an LSTM and an eLSTM agree with the IR reference in ONNX Runtime."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import onnx
import pytest

from snncc.ir.simulate import simulate
from snncc.targets.jetson import target
from snncc.targets.jetson.standalone_runner import ArtefactRunner
from tests.jetson.helpers import STEPS, seeded_inputs

ALL = ["rsnn", "ffsnn", "lstm", "elstm"]
SNNS = ["rsnn", "ffsnn"]
FILES = {"model.onnx", "step.onnx", "manifest.json", "build_engine.sh", "run.py"}


def reference(graph, x):
    k = graph.metadata.get("input_copies", 1) or 1
    tiled = np.tile(x, (1, 1, k)) if graph.node("input").width != x.shape[2] else x
    res = simulate(graph, tiled.astype(np.float64))
    return np.asarray(res.output), np.asarray(res.prediction)


@pytest.mark.parametrize("name", ALL)
def test_directory_holds_every_file(artefacts, name):
    _, _, path = artefacts[name]
    assert {p.name for p in path.iterdir()} == FILES


@pytest.mark.parametrize("name", ALL)
def test_sequence_model_agrees_with_ir_reference(artefacts, name):
    graph, _, path = artefacts[name]
    x = seeded_inputs(graph, 6, STEPS, seed=123)  # not the validation's seed
    ref_out, ref_pred = reference(graph, x)
    res = ArtefactRunner(str(path), backend="onnxruntime").run(x)
    np.testing.assert_array_equal(res["prediction"], ref_pred)
    if name in SNNS:
        spikes = res["output_spikes"]
        assert spikes.shape == ref_out.shape
        assert np.mean(spikes == ref_out) >= 0.999
        assert ref_out.sum() > 0, "test model must spike, else agreement is trivial"
        np.testing.assert_array_equal(res["counts"], ref_out.sum(axis=1))
    else:
        np.testing.assert_allclose(res["scores"], ref_out[:, -1], atol=1e-5)


@pytest.mark.parametrize("name", ALL)
def test_step_model_driven_for_t_steps_equals_sequence_model(artefacts, name):
    graph, _, path = artefacts[name]
    x = seeded_inputs(graph, 4, STEPS, seed=7)
    runner = ArtefactRunner(str(path), backend="onnxruntime")
    whole, streamed = runner.run(x), runner.stream(x)
    np.testing.assert_array_equal(streamed["prediction"], whole["prediction"])
    if name in SNNS:
        np.testing.assert_array_equal(streamed["output_spikes"], whole["output_spikes"])
        np.testing.assert_array_equal(streamed["counts"], whole["counts"])
    else:
        np.testing.assert_allclose(streamed["scores"], whole["scores"], atol=1e-5)


@pytest.mark.parametrize("name", SNNS)
def test_step_model_runs_any_length(artefacts, name):
    graph, _, path = artefacts[name]
    x = seeded_inputs(graph, 2, STEPS + 17, seed=9)
    ref_out, ref_pred = reference(graph, x)
    res = ArtefactRunner(str(path), backend="onnxruntime").stream(x)
    assert np.mean(res["output_spikes"] == ref_out) >= 0.999
    np.testing.assert_array_equal(res["prediction"], ref_pred)


@pytest.mark.parametrize("name", ["lstm", "elstm"])
def test_lstm_is_native_onnx_lstm_with_dynamic_batch_and_time(artefacts, name):
    graph, art, path = artefacts[name]
    ops = {n.op_type for n in onnx.load(path / "model.onnx").graph.node}
    assert "LSTM" in ops
    runner = ArtefactRunner(str(path), backend="onnxruntime")
    for batch, steps in ((1, 5), (3, 2 * STEPS)):
        x = seeded_inputs(graph, batch, steps, seed=batch)
        _, ref_pred = reference(graph, x)
        np.testing.assert_array_equal(runner.run(x)["prediction"], ref_pred)


@pytest.mark.parametrize("name", ALL)
def test_no_sequence_or_loop_operators_and_one_file(artefacts, name):
    _, _, path = artefacts[name]
    for f in ("model.onnx", "step.onnx"):
        model = onnx.load(path / f)
        onnx.checker.check_model(model)
        ops = {n.op_type for n in model.graph.node}
        assert not any(o.startswith("Sequence") or o in ("ConcatFromSequence", "Loop", "Scan") for o in ops)
        assert not any(i.data_location == onnx.TensorProto.EXTERNAL for i in model.graph.initializer)
        assert model.opset_import[0].version == 13
    assert not list(path.glob("*.data"))


@pytest.mark.parametrize("name", SNNS)
def test_spikes_export_as_greater_and_cast(artefacts, name):
    _, _, path = artefacts[name]
    ops = {n.op_type for n in onnx.load(path / "model.onnx").graph.node}
    assert {"Greater", "Cast"} <= ops


def test_manifest_describes_the_interface(artefacts):
    graph, art, path = artefacts["rsnn"]
    m = json.loads((path / "manifest.json").read_text())
    assert m["opset"] == 13 and m["jetpack"] == "4.6" and m["time_steps"] == STEPS
    assert m["dt"] == graph.dt and m["snncc_version"]
    assert m["input"] == {**m["input"], "channels": 6, "input_copies": 2, "graph_width": 12}
    seq = m["variants"][0]
    assert seq["inputs"] == [{"name": "events", "shape": ["batch", STEPS, 6], "dtype": "float32"}]
    assert [o["name"] for o in seq["outputs"]] == ["counts", "output_spikes"]
    assert seq["outputs"][1]["shape"] == ["batch", STEPS, 5]
    step = m["variants"][1]
    proto = onnx.load(path / "step.onnx")
    assert [i["name"] for i in step["inputs"]] == [i.name for i in proto.graph.input]
    assert [o["name"] for o in step["outputs"]] == [o.name for o in proto.graph.output]
    v = m["validation"]
    assert v["sequence"]["spike_agreement"] >= 0.999 and v["step"]["agreement_with_sequence_model"] == 1.0
    assert "spike_flips" in v["fp16"]
    # required against the float32 reference (the artefact's precision); float64 measured beside, not required
    assert v["reference"].startswith("snncc.ir.simulate in float32") and 0 <= v["sequence"]["float64"]["spike_agreement"] <= 1
    assert m["classes"] == graph.metadata["classes"]


def test_lowering_is_byte_identical(graphs, artefacts):
    again = target.lower(graphs["rsnn"], {"time_steps": STEPS})
    assert again.files == artefacts["rsnn"][1].files


@pytest.mark.parametrize("jetpack, opset", [("4.6.1", 13), ("5.1.2", 17), ("6.0", 17), ("6.1", 20), ("6.2", 20)])
def test_opset_follows_jetpack(jetpack, opset):
    from snncc.targets.jetson.export import opset_for_jetpack

    assert opset_for_jetpack(jetpack) == opset


def test_jetpack_6_exports_opset_20(graphs):
    art = target.lower(graphs["ffsnn"], {"time_steps": 8, "jetpack": "6.1"})
    assert art.manifest["opset"] == 20
    assert onnx.load_from_string(art.files["model.onnx"]).opset_import[0].version == 20


def test_runner_rejects_wrong_channels_and_length(artefacts):
    from snncc.targets.jetson.standalone_runner import RunnerError

    graph, _, path = artefacts["rsnn"]
    runner = ArtefactRunner(str(path), backend="onnxruntime")
    with pytest.raises(RunnerError, match="input copies"):
        runner.run(np.zeros((1, STEPS, 12), np.float32))
    with pytest.raises(RunnerError, match="streaming"):
        runner.run(np.zeros((1, STEPS + 1, 6), np.float32))


def test_standalone_run_py_runs_without_snncc(artefacts, tmp_path):
    graph, _, path = artefacts["rsnn"]
    x = seeded_inputs(graph, 3, STEPS, seed=11)
    np.save(tmp_path / "x.npy", x)
    out = tmp_path / "out.npz"
    proc = subprocess.run([sys.executable, str(path / "run.py"), "--input", str(tmp_path / "x.npy"), "-o", str(out)],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["backend"] == "onnxruntime"
    _, ref_pred = reference(graph, x)
    np.testing.assert_array_equal(np.load(out)["prediction"], ref_pred)
    text = (path / "run.py").read_text()
    assert "import snncc" not in text and "from snncc" not in text  # copied to the board alone


def test_build_engine_script_is_valid_bash_with_shapes(artefacts):
    _, _, path = artefacts["rsnn"]
    text = (path / "build_engine.sh").read_text()
    assert subprocess.run(["bash", "-n", str(path / "build_engine.sh")]).returncode == 0
    assert "--onnx=model.onnx --saveEngine=model.plan" in text
    assert f"--minShapes=events:1x{STEPS}x6" in text and f"--maxShapes=events:64x{STEPS}x6" in text
    assert "--fp16" in text and "--int8" in text and "calib" in text
    lstm_text = (artefacts["lstm"][2] / "build_engine.sh").read_text()
    assert f"--maxShapes=frames:64x{4 * STEPS}x12" in lstm_text


def test_build_engine_refuses_int8_without_calibration(artefacts, tmp_path):
    _, _, path = artefacts["ffsnn"]
    fake = tmp_path / "trtexec"
    fake.write_text("#!/bin/sh\necho \"$@\" >> \"$(dirname \"$0\")/calls\"\n")
    fake.chmod(0o755)
    env = {"PATH": "/usr/bin:/bin", "TRTEXEC": str(fake)}
    bad = subprocess.run(["bash", str(path / "build_engine.sh"), "--int8"], capture_output=True, text=True, env=env)
    assert bad.returncode == 2 and "calib" in bad.stderr
    ok = subprocess.run(["bash", str(path / "build_engine.sh"), "--fp16"], capture_output=True, text=True, env=env)
    assert ok.returncode == 0, ok.stderr
    calls = (tmp_path / "calls").read_text().splitlines()
    assert len(calls) == 2 and all("--fp16" in c for c in calls)
    assert any("--onnx=step.onnx" in c for c in calls)


def test_fp16_emulation_reports_flips(artefacts):
    fp16 = artefacts["rsnn"][1].manifest["validation"]["fp16"]
    assert fp16["spike_flips"] >= 0 and "predictions_changed" in fp16
    assert "float16" in fp16["method"]
