"""Time to classification: the rule, each model family's prefix predictions, the CLI and its figure."""

import json

import numpy as np
import torch

from snncc.cli.main import run
from snncc.models import LSTMClassifier
from snncc.models.baselines import BufferedClassifier
from snncc.training.trainer import build_model
from snncc.training.ttc import prefix_predictions, time_to_classification, ttc_of

from .conftest import toy_events


def test_ttc_rule_is_the_start_of_the_final_correct_run():
    preds = np.array([[1, 0, 0, 0],     # right from step 2 on -> 2/4
                      [0, 0, 0, 1],     # wrong at the end -> no TTC
                      [0, 0, 0, 0],     # right throughout -> 1/4
                      [0, 1, 0, 0]])    # right, wrong, right: the final run starts at step 3 -> 3/4
    ttc = ttc_of(preds, np.array([0, 0, 0, 0]))
    assert ttc[0] == 0.5 and np.isnan(ttc[1]) and ttc[2] == 0.25 and ttc[3] == 0.75


def test_lstm_prefixes_equal_the_model_on_truncated_input():
    torch.manual_seed(0)
    model = LSTMClassifier(n_inputs=12, n_hidden=16, n_outputs=5).eval()
    x = torch.randn(4, 9, 12)
    preds = prefix_predictions(model, x)
    for k in (1, 4, 9):
        with torch.no_grad():
            assert np.array_equal(preds[:, k - 1], model(x[:, :k]).argmax(1).numpy())


def test_spiking_prefixes_equal_the_model_on_truncated_input():
    torch.manual_seed(0)
    model = build_model("rsnn", n_inputs=24, n_hidden=30, n_outputs=5, input_copies=2)
    model.reset_parameters(4.0, 0.5)
    x = torch.from_numpy(toy_events(n_per_class=2, n_classes=3, steps=15)[0]).float()
    preds = prefix_predictions(model, x)
    with torch.no_grad():
        for k in (3, 15):
            counts = model(x[:, :k])[0].sum(1)
            assert np.array_equal(preds[:, k - 1], counts.argmax(1).numpy())


def test_buffered_prefixes_are_zero_padded():
    torch.manual_seed(0)
    model = BufferedClassifier(kind="fcn", n_steps=12, n_outputs=4).eval()
    x = torch.randn(3, 12, 12)
    preds = prefix_predictions(model, x)
    padded = torch.cat([x[:, :5], torch.zeros(3, 7, 12)], dim=1)
    with torch.no_grad():
        assert np.array_equal(preds[:, 4], model(padded).argmax(1).numpy())
    rec = time_to_classification(model, x, preds[:, -1], label="fcn")   # labels = its own final answers
    assert rec.final_accuracy == 1.0 and rec.never_correct_share == 0.0 and 0 < rec.mean_ttc <= 1
    assert rec.accuracy[-1] == 1.0 and len(rec.fractions) == 12


def test_cli_several_models_json_and_figure(tmp_path, capsys):
    from snncc.data.dataset_file import save_dataset
    from snncc.training.pipeline import TrainRequest, train

    x, y = toy_events(n_per_class=5, n_classes=27, steps=12)
    events = tmp_path / "events.npz"
    save_dataset(events, x, y, {"kind": "events", "threshold": 1, "time_bin_size_ms": 5, "dt_s": 0.005,
                                "synthetic": True, "source": "toy", "seed": 0})
    frames = tmp_path / "frames.npz"
    save_dataset(frames, x[..., :12].astype(np.float32) + np.float32(0.1), y,
                 {"kind": "frames", "threshold": None, "time_bin_size_ms": 25, "dt_s": 0.025, "synthetic": True,
                  "source": "toy", "seed": 0})
    ckpts = []
    for kind, data in (("elstm", events), ("fcn", frames)):
        out = tmp_path / f"{kind}.pt"
        train(TrainRequest(kind=kind, data=str(data), output=str(out), epochs=1, device="cpu"))
        ckpts.append(str(out))
    fig, out = tmp_path / "ttc.png", tmp_path / "ttc.json"
    assert run(["analyse", "ttc", *ckpts, "--data", str(frames), "--data", str(events), "--figure", str(fig),
                "-o", str(out), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    saved = json.loads(out.read_text())
    assert printed == saved and [m["kind"] for m in saved["models"]] == ["elstm", "fcn"]
    for m in saved["models"]:
        assert m["samples"] == 27 and len(m["accuracy"]) == m["steps"] == 12 and "SYNTHETIC" in m["data"]
        assert m["notes"] == ["the checkpoint's own test split"]
    assert fig.read_bytes()[:4] == b"\x89PNG"
    # bad input: one line, nothing written
    assert run(["analyse", "ttc", ckpts[1], "--data", str(events), "-o", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no --data set fits this fcn" in err
    assert run(["analyse", "ttc", ckpts[1], "--data", str(frames), "--figure", str(tmp_path / "f.gif")]) == 2
    assert "--figure" in capsys.readouterr().err
    assert not (tmp_path / "x.json").exists() and not (tmp_path / "f.gif").exists()
