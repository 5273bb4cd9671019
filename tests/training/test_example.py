"""The Braille example's bookkeeping: failures are reported, blocked steps skipped, the table labelled."""

import importlib.util
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "braille" / "run_pipeline.py"


def _module():
    spec = importlib.util.spec_from_file_location("run_pipeline", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod       # dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


def test_failed_steps_are_reported_and_dependants_skipped(tmp_path):
    rp = _module()
    p = rp.Pipeline(tmp_path, {"rsnn_epochs": 1}, 0)
    failed = p.api("train RSNN th1", "train", "rsnn", data=tmp_path / "missing.npz", output=tmp_path / "m.pt")
    assert failed.status == "failed" and failed.message.startswith("snncc: error: ") and "missing.npz" in failed.message
    skipped = p.api("compile RSNN Loihi", "compile", tmp_path / "m.pt", target="loihi", output=tmp_path / "x.net",
                    needs=("train RSNN th1",))
    assert skipped.status == "skipped" and "train RSNN th1" in skipped.message
    assert not (tmp_path / "x.net").exists()
    p.steps.append(rp.Step("check RSNN Loihi", [], "failed", 0.0, "snncc: error: x: no such file"))
    res = rp.results(p)
    assert "SYNTHETIC" in res["data"] and "TEST epoch" in res["selection"]
    rows = {r["model"]: r for r in res["rows"]}
    assert rows["RSNN th1, float (PyTorch, authors' order)"] == {
        "model": "RSNN th1, float (PyTorch, authors' order)", "ours_percent": None, "paper_percent": 79.90}
    text = rp.markdown(res)
    assert "| train RSNN th1 | failed |" in text and "| check RSNN Loihi | failed |" in text
    assert "78.32 %" in text and "96.92 %" in text and "82.31 %" in text


def test_baseline_rows_ttc_and_latency_are_reported_beside_the_paper(tmp_path):
    rp = _module()
    p = rp.Pipeline(tmp_path, {"baseline_epochs": 1}, 0)
    p.steps.append(rp.Step("train fcn", [], "ok", 1.0, "", {"parameters": 279451, "history": {"test_accuracy": 0.5}}))
    p.steps.append(rp.Step("train tcnn", [], "failed", 1.0, "snncc: error: boom"))
    p.steps.append(rp.Step("TTC", [], "ok", 1.0, "", {"models": [
        {"model": "fcn.pt", "kind": "fcn", "method": "zero-padded", "final_accuracy": 0.5, "mean_ttc": 0.8,
         "median_ttc": 0.9, "never_correct_share": 0.5, "samples": 10}]}))
    p.steps.append(rp.Step("bench Jetson artefacts", [], "ok", 1.0, "", {"models": [
        {"artefact": str(tmp_path / "fcn_jetson"), "kind": "fcn", "median_ms": 2.0, "spread_ms": 0.1,
         "ratio_to_reference": 1.0}]}))
    res = rp.results(p)
    rows = {r["model"]: r for r in res["rows"]}
    assert rows["FCN on frames (279,451 params; paper 280k)"]["ours_percent"] == 50.0
    assert rows["TCNN on frames (? params; paper 2,673)"] == {"model": "TCNN on frames (? params; paper 2,673)",
                                                              "ours_percent": None, "paper_percent": 83.4}
    assert not any(r["model"].startswith("ResNet") for r in res["rows"])   # not run: no row
    text = rp.markdown(res)
    assert "| fcn.pt | fcn | 50.0 % | 0.800 | 0.900 | 50.0 % |" in text
    assert "| fcn_jetson | fcn | 2.000 | 0.100 | 1.00 |" in text and "SYNTHETIC" in text


def test_results_state_what_the_small_rsnn_reaches(tmp_path):
    rp = _module()
    p = rp.Pipeline(tmp_path, {"repetitions": 40, "rsnn_epochs": 3}, 0)
    step = rp.Step("train RSNN th1", [], "ok", 1.0, "", {"epochs": [{"test_accuracy": a} for a in (0.05, 0.09, 0.14)],
                                                       "history": {"test_accuracy": 0.14}})
    p.steps.append(step)
    res = rp.results(p)
    assert res["learning"]["rsnn_test_percent_per_epoch"] == [5.0, 9.0, 14.0]
    text = rp.markdown(res)
    assert "5.0 % -> 9.0 % -> 14.0 %" in text and "chance 3.7 %" in text and "it is learning" in text
    step.record = {"epochs": [{"test_accuracy": 0.04}], "history": {"test_accuracy": 0.04}}
    assert "NOT clearly above chance" in rp.markdown(rp.results(p))


def test_results_say_where_training_ran(tmp_path):
    rp = _module()
    p = rp.Pipeline(tmp_path, {}, 0, device="cuda")
    assert rp.results(p)["training_device"] == "cuda (asked; no training step ran)"
    p.steps.append(rp.Step("train RSNN th1", [], "ok", 1.0, "", {"device": "cpu", "epochs": [], "history": {"test_accuracy": 0.5}}))
    p.steps.append(rp.Step("train LSTM", [], "ok", 1.0, "", {"device": "cuda:0", "epochs": [], "history": {"test_accuracy": 0.9}}))
    res = rp.results(p)
    assert res["training_device"] == "cpu, cuda:0"
    assert "trained on: cpu, cuda:0" in rp.markdown(res)


def test_a_bad_device_stops_the_pipeline_before_any_step(tmp_path, capsys):
    import pytest

    rp = _module()
    with pytest.raises(SystemExit) as ex:
        rp.main(["--out", str(tmp_path / "run"), "--device", "tpu"])
    assert ex.value.code == 2 and "--device: 'tpu' is not a device" in capsys.readouterr().err
    assert not (tmp_path / "run").exists()
