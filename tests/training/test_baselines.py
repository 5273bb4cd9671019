"""The paper's buffered time-series classifiers: parameter counts, training, Jetson export, bad records."""

import json

import numpy as np
import pytest
import torch

from snncc.cli.main import run
from snncc.frontends.checkpoint import module_from_checkpoint
from snncc.models.baselines import BASELINE_KINDS, BufferedClassifier, keras_total
from snncc.models.lstm import count_trainable
from snncc.training.pipeline import TrainRequest, train
from snncc.training.trainer import build_model

# (trainable, Keras total incl. BatchNorm running statistics) on 12 taxels x 54 frames, 27 classes
COUNTS = {"fcn": (279_451, 280_475), "resnet": (513_819, 516_379), "inception": (452_251, 454_299),
          "encoder": (3_280_411, 3_280_411), "tcnn": (2_997, 2_997)}


@pytest.mark.parametrize("kind", BASELINE_KINDS)
def test_parameter_counts_on_the_paper_input(kind):
    model = build_model(kind, n_inputs=12, n_steps=54, n_outputs=27)
    assert (count_trainable(model), keras_total(model)) == COUNTS[kind]
    assert model(torch.zeros(2, 54, 12)).shape == (2, 27)


def test_counts_match_the_paper_where_stated():
    paper = {"fcn": 280_000, "resnet": 516_000, "inception": 452_000}
    assert round(keras_total(BufferedClassifier(kind="fcn")), -3) == paper["fcn"]
    assert round(keras_total(BufferedClassifier(kind="resnet")), -3) == paper["resnet"]     # Keras "Total params"
    assert round(count_trainable(BufferedClassifier(kind="inception")), -3) == paper["inception"]
    # the family's default kernels (40/20/10) would give 495k, not the paper's 452k
    assert count_trainable(BufferedClassifier(kind="inception", longest_kernel=40)) == 495_259
    # TCNN's 2,673 is the count with a pooled length of 5 (45..53 input frames), not 54
    assert count_trainable(BufferedClassifier(kind="tcnn", n_steps=50)) == 2_673
    enc = count_trainable(BufferedClassifier(kind="encoder")) / count_trainable(BufferedClassifier(kind="fcn"))
    assert 10 <= enc < 13          # "one order of magnitude" above FCN


def _frames(n_per_class=5, n_classes=27, steps=54, seed=0):
    """Separable toy frames: class c raises taxel c % 12 in its own time window."""
    rng = np.random.default_rng(seed)
    y = np.repeat(np.arange(n_classes), n_per_class)
    x = rng.standard_normal((y.size, steps, 12)).astype(np.float32) * 0.1
    for i, c in enumerate(y):
        start = (c // 12) * (steps // 3)
        x[i, start:start + steps // 3, c % 12] += 2.0
    return x, y


def _write_frames(path):
    from snncc.data.dataset_file import save_dataset

    x, y = _frames()
    save_dataset(path, x, y, {"kind": "frames", "threshold": None, "time_bin_size_ms": 25, "dt_s": 0.025,
                              "synthetic": True, "source": "toy", "seed": 0})
    return path


@pytest.fixture(scope="module")
def frames_set(tmp_path_factory):
    return _write_frames(tmp_path_factory.mktemp("frames") / "frames.npz")


@pytest.mark.parametrize("kind", ["fcn", "tcnn", "encoder"])
def test_train_compile_and_onnx_agree(kind, frames_set, tmp_path, capsys):
    ckpt, art = tmp_path / f"{kind}.pt", tmp_path / f"{kind}_jetson"
    assert run(["train", kind, "--data", str(frames_set), "--epochs", "1", "--batch-size", "32", "-o", str(ckpt),
                "--device", "cpu", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["parameters"] == COUNTS[kind][0]
    meta = torch.load(ckpt, weights_only=True)["metadata"]
    assert record["device"] == meta["trained_on"] == "cpu"     # where it ran, said in --json and the checkpoint
    assert meta["optimiser"]["optimiser"] == "adam" and meta["optimiser"]["batch_size"] == 32
    assert run(["compile", str(ckpt), "--target", "jetson", "-o", str(art), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    v = summary["validation"]
    assert v["prediction_agreement"] == 1.0 and v["max_abs_delta_score"] < 1e-3
    # the artefact runs in the runner and reproduces PyTorch on the training data
    from snncc.targets.jetson.standalone_runner import ArtefactRunner

    x, _ = _frames()
    module = module_from_checkpoint(torch.load(ckpt, weights_only=True)).eval()
    with torch.no_grad():
        ref = module(torch.from_numpy(x[:5])).numpy()
    got = ArtefactRunner(str(art), backend="onnxruntime").run(x[:5])["scores"]
    np.testing.assert_allclose(got, ref, atol=1e-4)


def test_family_schedule_and_seeding(frames_set, tmp_path):
    from snncc.training.training_set import load_training_data
    from snncc.training.pipeline import optimiser_record

    rec = optimiser_record(TrainRequest(kind="inception", data="", output=""), 300)
    assert (rec["optimiser"], rec["lr"], rec["batch_size"], rec["plateau"]) == ("adam", 1e-3, 64, (0.5, 50, 1e-4))
    rec = optimiser_record(TrainRequest(kind="encoder", data="", output="", lr=1e-4, batch_size=8), 300)
    assert (rec["lr"], rec["batch_size"], rec["plateau"]) == (1e-4, 8, None)
    assert optimiser_record(TrainRequest(kind="tcnn", data="", output=""), 1)["loss"] == "mse_sigmoid"
    data = load_training_data(frames_set, "tcnn", 1, 5)
    runs = []
    for i in range(2):
        out = tmp_path / f"r{i}.pt"
        res = train(TrainRequest(kind="tcnn", data=str(frames_set), output=str(out), epochs=2, seed=3, device="cpu"),
                    data=data)
        runs.append(torch.load(out, weights_only=True)["state_dict"])
        assert res.optimiser["optimiser"] == "adam" and res.optimiser["batch_size"] == 16
    assert all(torch.equal(runs[0][k], runs[1][k]) for k in runs[0])


def test_bad_records_and_kinds_give_one_line(frames_set, tmp_path, capsys):
    assert run(["train", "vgg", "--data", str(frames_set), "-o", str(tmp_path / "x.pt")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    ckpt = tmp_path / "t.pt"
    train(TrainRequest(kind="tcnn", data=str(frames_set), output=str(ckpt), epochs=1, device="cpu"))
    obj = torch.load(ckpt, weights_only=True)
    for key, value in (("n_steps", 10**9), ("n_outputs", -3), ("n_inputs", 2.5), ("longest_kernel", True)):
        bad = {**obj, "architecture": {**obj["architecture"], key: value}}
        path = tmp_path / f"bad_{key}.pt"
        torch.save(bad, path)
        assert run(["compile", str(path), "--target", "jetson", "-o", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"architecture.{key}" in err
    assert run(["compile", str(ckpt), "--target", "loihi", "-o", str(tmp_path / "x.net")]) == 2
    assert "only with --target jetson" in capsys.readouterr().err
    assert run(["compile", str(ckpt), "--target", "jetson", "--scale", "global", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scale: does not apply to --target jetson" in err
    assert not (tmp_path / "out").exists() and not (tmp_path / "x.net").exists()


@pytest.mark.parametrize("kind", ["resnet", "inception"])
def test_residual_networks_export_and_agree(kind, tmp_path):
    from snncc.frontends.buffered import BufferedModel
    from snncc.targets.jetson import target

    torch.manual_seed(0)
    module = BufferedClassifier(kind=kind, n_steps=20)
    art = target.lower(BufferedModel(module), {"jetpack": "5.1"})
    v = art.manifest["validation"]
    assert art.manifest["opset"] == 17 and v["prediction_agreement"] == 1.0 and v["max_abs_delta_score"] < 1e-3
    art.write(tmp_path / "a")
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["build_engine.sh", "manifest.json", "model.onnx", "run.py"]


def test_bench_times_baselines_beside_an_lstm_in_one_run(tmp_path, capsys):
    from snncc.frontends import graph_from_object
    from snncc.models import LSTMClassifier
    from snncc.frontends.buffered import BufferedModel
    from snncc.targets.jetson import target

    torch.manual_seed(0)
    lstm = LSTMClassifier(n_inputs=12, n_hidden=8, n_outputs=27)
    target.lower(graph_from_object(lstm), {"time_steps": 12}).write(tmp_path / "lstm")
    target.lower(BufferedModel(BufferedClassifier(kind="tcnn", n_steps=12))).write(tmp_path / "tcnn")
    args = ["bench", str(tmp_path / "lstm"), str(tmp_path / "tcnn"), "--samples", "3", "--repeats", "1",
            "--warmup-passes", "0", "--timed-passes", "1"]
    assert run([*args, "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert [m["kind"] for m in record["models"]] == ["lstm", "tcnn"]
    assert record["models"][0]["ratio_to_reference"] == 1.0 and record["models"][1]["median_ms"] > 0
    assert run([*args, "--stream"]) == 2
    assert "no step variant" in capsys.readouterr().err
    import snncc.api as api

    calls = []
    api.bench([tmp_path / "lstm", tmp_path / "tcnn"], samples=3, repeats=1, warmup_passes=1, timed_passes=1,
              progress=lambda *c: calls.append(c))
    assert calls[-1] == (12, 12, "tcnn: timing")   # 2 x (3 + 3); each phase names its artefact
    assert {c[2] for c in calls} == {"lstm: warm-up", "lstm: timing", "tcnn: warm-up", "tcnn: timing"}
