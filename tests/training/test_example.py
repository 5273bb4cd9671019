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
         "ratio_to_reference": 1.0, "data": "SYNTHETIC inputs (seeded random, 32 samples, seed 0): latency only"}]}))
    res = rp.results(p)
    rows = {r["model"]: r for r in res["rows"]}
    assert rows["FCN on frames (279,451 params; paper 280k)"]["ours_percent"] == 50.0
    assert rows["TCNN on frames (? params; paper 2,673)"] == {"model": "TCNN on frames (? params; paper 2,673)",
                                                              "ours_percent": None, "paper_percent": 83.4}
    assert not any(r["model"].startswith("ResNet") for r in res["rows"])   # not run: no row
    text = rp.markdown(res)
    assert "| fcn.pt | fcn | 50.0 % | 0.800 | 0.900 | 50.0 % |" in text
    assert "| fcn_jetson | fcn | SYNTHETIC (random) | 2.000 | 0.100 | 1.00 |" in text and "SYNTHETIC" in text


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


def _epochs(*accs):
    return [{"epoch": i + 1, "loss": 30.0 / (i + 1), "nll": 3.0, "train_accuracy": a * 0.9, "test_accuracy": a,
             "val_accuracy": None, "hidden_spikes_per_sample": 1.0, "seconds": 1.0} for i, a in enumerate(accs)]


def _reader_pipeline(rp, tmp_path, small_rsnn_checkpoint):
    """A pipeline whose training and check steps are records as the verbs write them, and whose map and
    energy steps really run on a small bundle."""
    import snncc.api

    p = rp.Pipeline(tmp_path, {"repetitions": 40, "rsnn_epochs": 3}, 0)
    for name, accs in (("train RSNN th1", (0.05, 0.1, 0.2)), ("train RSNN QAT", (0.22,)), ("train LSTM", (0.3, 0.5)),
                       ("train eLSTM", (0.06,))):
        p.steps.append(rp.Step(name, [], "ok", 1.0, "", {"epochs": _epochs(*accs), "device": "cpu",
                                                        "history": {"test_accuracy": max(accs)},
                                                        "quantization": {"after": {"quantized_test_accuracy": 0.21}}}))
    # check records as `snncc check --json` writes them (the kit's CheckReport)
    p.steps.append(rp.Step("check RSNN Loihi", [], "ok", 1.0, "", {
        "accuracy": {"float": 0.2, "artefact": 0.17},
        "details": {"accuracy_by_stage": {"float_trained": 0.2, "ir_quantized": 0.18, "emulator_wide": 0.17,
                                          "emulator": 0.17}}}))
    p.steps.append(rp.Step("check RSNN Jetson", [], "ok", 1.0, "", {"accuracy": {"float": 0.2, "artefact": 0.2}}))
    p.steps.append(rp.Step("check LSTM Jetson", [], "ok", 1.0, "", {"accuracy": {"float": 0.5, "artefact": 0.5}}))
    # compare records as `snncc compare --json` writes them (rows per target)
    p.steps.append(rp.Step("compare RSNN", [], "ok", 1.0, "", {"rows": [
        {"target": "loihi", "accuracy": 0.17, "energy": {"uj_per_sample": 0.5, "source": "estimate"}},
        {"target": "jetson", "accuracy": 0.2}]}))
    p.steps.append(rp.Step("compare LSTM", [], "ok", 1.0, "", {"rows": [{"target": "jetson", "accuracy": 0.5}]}))
    bundle = tmp_path / "rsnn_th1.net"
    snncc.api.compile(small_rsnn_checkpoint, target="loihi", output=bundle)
    (tmp_path / rp.FIGURES).mkdir()
    assert p.api("map RSNN Loihi", "map", bundle, plot=tmp_path / rp.FIGURES / "core_map.png").status == "ok"
    assert p.api("energy RSNN Loihi", "report", bundle, energy=True, samples=2).status == "ok"
    return p


def test_results_hold_the_papers_figures_and_draw_them(tmp_path, small_rsnn_checkpoint, capsys):
    """Training curves, accuracy per model and deployment beside the paper, the core map, energy and delay
    (ESTIMATE beside the paper's MEASUREMENT): in results.json/results.md and as PNGs linked from results.md."""
    rp = _module()
    p = _reader_pipeline(rp, tmp_path, small_rsnn_checkpoint)
    res = rp.results(p)
    rows = {r["model"]: r for r in res["accuracy_by_model"]}
    assert rows["RSNN th1"] == {"model": "RSNN th1", "float": 20.0, "quantized": 18.0, "loihi_emulated": 17.0,
                                "jetson": 20.0, "paper_float": 79.90, "paper_loihi": 78.32}
    assert rows["LSTM (frames)"]["jetson"] == 50.0 and rows["LSTM (frames)"]["paper_float"] == 96.92
    assert [c["model"] for c in res["training_curves"]] == ["RSNN th1", "RSNN th1 QAT", "LSTM", "eLSTM"]
    assert [e["test_accuracy"] for e in res["training_curves"][0]["epochs"]] == [0.05, 0.1, 0.2]
    loihi = res["loihi"]
    assert loihi["core_map"]["cores"] >= 1 and loihi["core_map"]["paper_cores"] == 8
    assert loihi["estimate"]["energy_uj_per_sample"] > 0 and "ESTIMATE" in loihi["estimate"]["label"]
    assert loihi["estimate"]["paper_measurement"]["energy_uj_per_sample"] == 71.0
    cmp = res["paper_comparison"]
    assert cmp["rsnn_loihi_accuracy"] == 0.17 and cmp["lstm_jetson_accuracy"] == 0.5
    assert cmp["ratio"] == 35212.0 / 0.5 and cmp["paper_ratio"] == 496

    figures = rp.write_figures(p, res)
    assert list(figures) == ["training_curves", "accuracy", "core_map", "energy_delay"]
    for path, _ in figures.values():
        assert (tmp_path / path).read_bytes()[:4] == b"\x89PNG", path
    assert all(p.status(f"figure {n}") == "ok" for n in ("training_curves", "accuracy", "energy_delay"))
    text = rp.markdown(rp.results(p) | {"figures": figures})
    for path, _ in figures.values():
        assert f"]({path})" in text
    assert "| RSNN th1 | 20.00 % | 18.00 % | 17.00 % | 20.00 % | 79.90 % | 78.32 % |" in text
    assert "snncc ESTIMATE" in text and "paper, measured" in text and "| energy per sample |" in text
    assert "| delay per sample |" in text and "71 uJ" in text and "2.3 ms" in text
    assert "| accuracy, this run | 17.00 % (bit-exact emulator) | 50.00 % (ONNX Runtime) | |" in text
    assert "ESTIMATE against measurement" in text and "| 496x |" in text


def test_figures_are_labelled_and_their_tick_labels_readable(tmp_path, small_rsnn_checkpoint):
    import matplotlib.pyplot as plt

    from snncc.log_axis import overlapping_labels

    rp = _module()
    figs = rp.pipeline_figures
    res = rp.results(_reader_pipeline(rp, tmp_path, small_rsnn_checkpoint))
    built = {"training": figs.training_curves_figure(res["training_curves"], rp.CHANCE_PERCENT),
             "accuracy": figs.accuracy_figure(res["accuracy_by_model"]),
             "energy": figs.energy_delay_figure(res["loihi"]["estimate"])}
    try:
        for name, fig in built.items():
            title = fig._suptitle.get_text() if fig._suptitle else fig.axes[0].get_title()
            assert "SYNTHETIC" in title, name
            for ax in fig.axes:
                assert overlapping_labels(ax, "x") == [] and overlapping_labels(ax, "y") == [], name
        assert "ESTIMATE" in built["energy"]._suptitle.get_text() and "MEASUREMENT" in built["energy"]._suptitle.get_text()
        assert [t.get_text() for t in built["energy"].axes[0].get_xticklabels()] == ["snncc\nESTIMATE", "paper\nMEASURED"]
    finally:
        for fig in built.values():
            plt.close(fig)
    assert figs.training_curves_figure([], 3.7) is None and figs.energy_delay_figure(None) is None


def test_long_steps_print_progress_lines(tmp_path, monkeypatch, capsys):
    """A verb that takes progress / on_epoch gets them: one line per epoch as `snncc train` prints it, and when
    stdout is not a terminal a progress line at most every PROGRESS_EVERY_S seconds."""
    import types

    import snncc.api

    rp = _module()
    calls = {}

    def fake_train(model, *, data, progress=None, on_epoch=None):
        calls["train"] = (progress is not None, on_epoch is not None)
        for e in (1, 2):
            progress(e, 2, f"epoch {e}/2")
            on_epoch(types.SimpleNamespace(epoch=e, loss=1.5 / e, train_accuracy=0.1 * e, test_accuracy=0.2 * e,
                                           val_accuracy=None, seconds=0.5))
        return types.SimpleNamespace(as_dict=lambda: {"ok": True})

    def fake_generate(*, out):
        calls["generate"] = True
        return types.SimpleNamespace(as_dict=lambda: {"out": out})

    monkeypatch.setattr(snncc.api, "train", fake_train, raising=False)
    monkeypatch.setattr(snncc.api, "data_synth", fake_generate, raising=False)
    monkeypatch.setattr(rp, "PROGRESS_EVERY_S", 0.0)
    p = rp.Pipeline(tmp_path, {}, 0)
    assert p.api("train RSNN th1", "train", "rsnn", data="d.npz").status == "ok"
    assert p.api("generate", "data_synth", out="x").status == "ok"      # takes neither: called without them
    out = capsys.readouterr().out
    assert calls == {"train": (True, True), "generate": True}
    assert "       train RSNN th1: epoch 1: loss 1.5000  train 10.00 %  test 20.00 %  (0.5 s)\n" in out
    assert "       train RSNN th1: epoch 2: loss 0.7500  train 20.00 %  test 40.00 %  (0.5 s)\n" in out
    assert "       train RSNN th1: epoch 1/2 1/2\n" in out and "\r" not in out      # not a terminal: whole lines


def test_progress_on_a_terminal_is_rewritten_in_place():
    import io

    rp = _module()

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    term = Terminal()
    shows = rp.StepProgress("check RSNN Jetson", stream=term)
    shows.progress(1, 4, "checking")
    shows.progress(2, 4, "checking")
    shows.close()
    assert term.getvalue() == ("\r\033[K       check RSNN Jetson: checking 1/4\r\033[K       check RSNN Jetson: checking 2/4"
                               "\r\033[K")
