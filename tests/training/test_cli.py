"""``snncc train`` end to end: checkpoints that snncc compile takes; bad input gives one line."""

import json

import numpy as np
import pytest
import torch

from snncc.cli.main import run
from snncc.frontends.checkpoint import module_from_checkpoint
from snncc.ir.serialize import load_graph
from snncc.ir.simulate import simulate
from snncc.training.training_set import TrainingData
from snncc.training.pipeline import TrainRequest, finetune, train

from .conftest import toy_events


def _toy_data(n_per_class=10, n_classes=27, steps=12):
    x, y = toy_events(n_per_class=n_per_class, n_classes=n_classes, steps=steps)
    meta = {"kind": "events", "threshold": 1, "time_bin_size_ms": 5, "synthetic": True, "classes": [str(i) for i in range(n_classes)]}
    return TrainingData(torch.from_numpy(x), torch.from_numpy(y), meta, "toy")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    out = tmp_path_factory.mktemp("train") / "rsnn.pt"
    req = TrainRequest(kind="ffsnn", data="toy", output=str(out), epochs=1, batch_size=64, seed=0)
    result = train(req, data=_toy_data())
    return out, result


def test_checkpoint_records_data_facts_and_selection(trained):
    out, result = trained
    obj = torch.load(out, weights_only=True)
    meta = obj["metadata"]
    assert obj["architecture"]["kind"] == "ffsnn" and obj["architecture"]["input_copies"] == 2
    assert meta["threshold"] == 1 and meta["time_bin_size_ms"] == 5 and meta["dt"] == 0.005
    assert meta["synthetic_data"] is True and meta["encoding"] == "events"
    assert meta["split_seed"] == 0 and meta["best_epoch"] == 1 and meta["epoch_selected_on"] == "test"
    assert "TEST" in meta["selection_note"]
    assert meta["preset"]["tau_mem"] == 0.06 and meta["update_order"] == "spytorch"
    assert len(meta["classes"]) == 28 and meta["classes"][-1] == "spare"
    assert result.parameters == 48 * 450 + 450 * 28


def test_compile_takes_the_checkpoint_and_the_ir_reproduces_the_model(trained, tmp_path):
    out, _ = trained
    ir_file = tmp_path / "m.snnir"
    assert run(["compile", str(out), "--target", "ir", "-o", str(ir_file), "--json"]) == 0
    graph = load_graph(ir_file)
    model = module_from_checkpoint(torch.load(out, weights_only=True)).double()
    x = torch.from_numpy(toy_events(n_per_class=1, n_classes=4, steps=30)[0]).double()
    out_spikes, _ = model(x)
    sim = simulate(graph, np.tile(x.numpy(), (1, 1, 2)), dtype=torch.float64)
    assert np.array_equal(np.asarray(sim.output), out_spikes.detach().numpy())


def test_qat_finetunes_on_the_same_split_and_records_both_losses(trained, tmp_path):
    src, _ = trained
    out = tmp_path / "qat.pt"
    req = TrainRequest(kind="ffsnn", data="toy", output=str(out), batch_size=64, qat_from=str(src), qat_epochs=1)
    result = finetune(req, data=_toy_data())
    q = result.quantization
    assert set(q) >= {"before", "after", "loss_before_points", "loss_after_points"}
    assert q["before"]["quantization"]["i_decay"] == 2315
    meta = torch.load(out, weights_only=True)["metadata"]
    assert meta["qat"]["epochs"] == 1 and meta["split"] == result.split
    assert result.split["test"] == 54
    before = torch.load(src, weights_only=True)["metadata"]["split_assignment"]
    assert meta["split_assignment"] == before and len(before) == 270
    assert before.count("t") == 54 and before.count("r") == 216


def test_bad_inputs_give_one_line(tmp_path, capsys):
    out = tmp_path / "x.pt"
    assert run(["train", "rsnn", "--data", str(tmp_path / "missing.npz"), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("snncc: error:") and "missing.npz" in err and err.count("\n") == 1
    assert run(["train", "rsnn", "--data", str(tmp_path), "-o", str(out), "--set", "tau=1"]) == 2
    assert "unknown hyper-parameter" in capsys.readouterr().err
    assert run(["train", "rsnn", "--data", str(tmp_path), "-o", str(out), "--threshold", "3"]) == 2
    assert "no paper preset" in capsys.readouterr().err
    not_ckpt = tmp_path / "weights.pt"
    torch.save([torch.zeros(2, 2)], not_ckpt)
    assert run(["train", "rsnn", "--data", str(tmp_path), "-o", str(out), "--qat-from", str(not_ckpt)]) == 2
    assert "not an snncc checkpoint" in capsys.readouterr().err
    assert not out.exists()


def test_lstm_cannot_be_fine_tuned_for_loihi(tmp_path, capsys):
    ckpt = tmp_path / "lstm.pt"
    x = np.random.default_rng(0).random((135, 20, 12)).astype(np.float32)
    y = np.repeat(np.arange(27), 5)
    data = TrainingData(torch.from_numpy(x), torch.from_numpy(y), {"synthetic": True}, "toy")
    train(TrainRequest(kind="lstm", data="toy", output=str(ckpt), epochs=1), data=data)
    assert run(["train", "lstm", "--data", str(tmp_path), "-o", str(tmp_path / "q.pt"), "--qat-from", str(ckpt)]) == 2
    assert "rsnn/ffsnn" in capsys.readouterr().err


def _write_set(path, kind="events", time_bin=5, threshold=1):
    from snncc.data.dataset_file import save_dataset

    x, y = toy_events(n_per_class=6, n_classes=27, steps=12)
    if kind == "frames":
        x = x[..., :12].astype(np.float32)
    meta = {"kind": kind, "threshold": threshold if kind == "events" else None, "time_bin_size_ms": time_bin,
            "dt_s": time_bin / 1000, "synthetic": True, "source": "toy", "seed": 0}
    save_dataset(path, x, y, meta)
    return path


def test_cli_trains_from_an_encoded_set_and_prints_json(tmp_path, capsys):
    data = _write_set(tmp_path / "events.npz")
    out = tmp_path / "ff.pt"
    code = run(["train", "ffsnn", "--data", str(data), "--epochs", "1", "--subset", "150", "--seed", "2",
                "--order", "loihi", "-o", str(out), "--json"])
    assert code == 0
    record = json.loads(capsys.readouterr().out)
    assert record["split"] == {"train": 120, "val": 0, "test": 30, "seed": 2, "test_fraction": 0.2, "val_fraction": 0.0}
    assert record["history"]["selected_on"] == "test" and "TEST" in record["history"]["note"]
    meta = torch.load(out, weights_only=True)["metadata"]
    assert meta["update_order"] == "loihi" and meta["subset"] == 150 and meta["data"]["source"] == str(data)
    assert meta["split_assignment"].count("-") == 12
    # fine-tuning from it reuses exactly that split (the 12 samples outside the subset stay unused)
    qat = tmp_path / "ff_qat.pt"
    assert run(["train", "ffsnn", "--data", str(data), "--qat-from", str(out), "--qat-epochs", "1", "-o", str(qat), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["split"]["test"] == 30 and record["quantization"]["epochs"] == 1
    assert torch.load(qat, weights_only=True)["metadata"]["split_assignment"] == meta["split_assignment"]


def test_cli_refuses_data_of_the_wrong_kind(tmp_path, capsys):
    frames = _write_set(tmp_path / "frames.npz", kind="frames")
    out = tmp_path / "m.pt"
    assert run(["train", "rsnn", "--data", str(frames), "-o", str(out)]) == 2
    assert "needs events" in capsys.readouterr().err
    events3 = _write_set(tmp_path / "ev3.npz", time_bin=3)
    assert run(["train", "rsnn", "--data", str(events3), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "meta.time_bin_size_ms" in err and "--set time_bin_size=3" in err
    events = _write_set(tmp_path / "ev.npz")
    assert run(["train", "lstm", "--data", str(events), "-o", str(out)]) == 2
    assert "use elstm" in capsys.readouterr().err
    assert run(["train", "rsnn", "--data", str(events), "-o", str(out), "--threshold", "2"]) == 2
    assert "threshold" in capsys.readouterr().err
    assert not out.exists()


@pytest.fixture(scope="module")
def synthetic_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("synth") / "braille"
    assert run(["data", "synth", "-o", str(d), "-n", "5", "--thresholds", "1", "--json"]) == 0
    return d


@pytest.mark.parametrize("kind", ["ffsnn", "lstm"])
def test_cli_encodes_a_directory_of_pickles_on_the_fly(synthetic_dir, tmp_path, capsys, kind):
    out = tmp_path / f"{kind}.pt"
    capsys.readouterr()
    assert run(["train", kind, "--data", str(synthetic_dir), "--epochs", "1", "-o", str(out), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)       # the encoder's own summary does not leak into ours
    assert record["data"]["samples"] == 135 and record["data"]["synthetic"] is True
    meta = torch.load(out, weights_only=True)["metadata"]
    if kind == "ffsnn":
        assert (record["data"]["steps"], record["data"]["channels"]) == (270, 24)
        assert meta["data"]["time_bin_size_ms"] == 5 and meta["data"]["threshold"] == 1
    else:
        assert (record["data"]["steps"], record["data"]["channels"]) == (54, 12)
        assert meta["encoding"] == "frames" and meta["dt"] == 0.025
    assert list(tmp_path.iterdir()) == [out]            # no temporary file left behind
