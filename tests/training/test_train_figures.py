"""bench/studies/train_figures.py: a tiny run writes the record, per epoch and at the end, with verdicts on
the selected epoch; a reused set (--data) gives the same figures as a freshly generated one."""

import json

import pytest

from snncc_test_helpers import load_bench


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("figures")
    tf = load_bench("studies/train_figures")
    out = tmp / "fresh.json"
    assert tf.main(["--reps", "5", "--rsnn-epochs", "2", "--lstm-epochs", "1", "--device", "cpu",
                    "--out", str(out)]) == 0
    return tf, tmp, json.loads(out.read_text())


def test_record_has_every_epoch_and_verdicts_on_the_selected_epoch(tiny_run):
    _, _, rec = tiny_run
    assert rec["synthetic"] is True and rec["generator_version"] == 2 and rec["repetitions"] == 5
    assert rec["run"].startswith("short run")                     # 5 repetitions, 2 epochs: not the protocol
    rsnn = rec["rsnn_th1"]
    assert rsnn["device"] == "cpu" and rsnn["epochs_done"] == 2 and len(rsnn["per_epoch"]) == 2
    assert all("hidden_spikes_per_sample" in e and "loss" in e for e in rsnn["per_epoch"])
    v = rec["verdicts"]["rsnn_th1"]
    best = rsnn["history"]["best_epoch"]
    assert v["selected_epoch"] == best
    assert v["selected_pct"] == pytest.approx(rsnn["test_accuracy_per_epoch_pct"][best - 1])
    assert v["max_pct"] == max(rsnn["test_accuracy_per_epoch_pct"])
    assert v["within_tolerance"] == (abs(v["selected_pct"] - 79.9) <= 5.0)
    assert v["never_above_88"] == (v["max_pct"] <= 88.0) and v["protocol_complete"] is False
    assert rec["verdicts"]["lstm_frames"]["protocol_complete"] is False


def test_a_reused_set_gives_the_same_figures(tiny_run, tmp_path):
    tf, _, fresh = tiny_run
    import snncc.api as api

    api.data_synth(out=tmp_path / "set", repetitions=5, seed=0, thresholds="1")
    out = tmp_path / "reused.json"
    assert tf.main(["--data", str(tmp_path / "set"), "--skip", "lstm", "--rsnn-epochs", "2", "--device", "cpu",
                    "--out", str(out)]) == 0
    reused = json.loads(out.read_text())
    assert reused["repetitions"] == 5 and reused["seed"] == reused["train_seed"] == 0 and "lstm_frames" not in reused
    assert reused["rsnn_th1"]["test_accuracy_per_epoch_pct"] == fresh["rsnn_th1"]["test_accuracy_per_epoch_pct"]


@pytest.mark.parametrize("args, says", [
    (["--device", "gpu"], "--device: 'gpu' is not a device"),
    (["--lr", "0"], "--lr: must be > 0"),
    (["--data", "NOWHERE"], "no SYNTHETIC.json"),
])
def test_bad_options_are_one_line_and_exit_2_before_anything_runs(args, says, tmp_path, capsys):
    tf = load_bench("studies/train_figures")
    out = tmp_path / "r.json"
    argv = [a.replace("NOWHERE", str(tmp_path / "none")) for a in args]
    with pytest.raises(SystemExit) as ex:
        tf.main(argv + ["--out", str(out)])
    assert ex.value.code == 2 and says in capsys.readouterr().err and not out.exists()
