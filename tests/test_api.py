"""The model and data verbs from Python (``snncc.api``): each record's ``as_dict()`` is the command's
``--json`` output and ``render_text`` its text, on small seeded inputs."""

from __future__ import annotations

import io
import json
import subprocess
import sys

import numpy as np
import pytest

import snncc.api as api
from snncc.errors import SnnccError

from snncc_test_helpers import run_cli

MODEL_DATA_VERBS = {"inspect", "export", "data_synth", "data_encode", "data_frames", "data_analyse", "train",
                    "analyse_ttc", "hpo_run", "hpo_report", "hpo_space"}


def cli_json(args, capsys):
    capsys.readouterr()
    code, out, err = run_cli([*args, "--json"], capsys)
    assert code == 0, err
    return json.loads(out)


def cli_text(args, capsys):
    capsys.readouterr()
    code, out, err = run_cli(args, capsys)
    assert code == 0, err
    return out


def text_of(record) -> str:
    """What ``record.render_text`` prints on a console like the CLI's (same width, no colour)."""
    from rich.console import Console

    from snncc.cli.output import console

    buf = io.StringIO()
    record.render_text(Console(file=buf, width=console.width, highlight=False))
    return buf.getvalue()


def without(d: dict, *keys: str) -> dict:
    return {k: v for k, v in d.items() if k not in keys}


def test_every_model_and_data_verb_is_in_the_api_and_importing_it_is_light():
    assert MODEL_DATA_VERBS <= set(api.__all__) and MODEL_DATA_VERBS <= set(dir(api))
    assert all(callable(getattr(api, name)) for name in MODEL_DATA_VERBS)
    with pytest.raises(AttributeError):
        api.no_such_verb
    probe = ("import sys, snncc.api as a; [getattr(a, n) for n in a.__all__]; "
             "print(sorted({m.split('.')[0] for m in sys.modules} & {'torch', 'sklearn', 'scipy', 'pandas', "
             "'onnx', 'onnxruntime', 'matplotlib', 'optuna'}))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"          # resolving the functions imports nothing heavy


def test_inspect_and_export(small_rsnn_checkpoint, tmp_path, capsys):
    rec = api.inspect(small_rsnn_checkpoint)
    assert rec.as_dict() == cli_json(["inspect", small_rsnn_checkpoint], capsys)
    assert rec.summary["neurons"] == 32 + 28 and rec.notes == []
    assert text_of(rec) == cli_text(["inspect", small_rsnn_checkpoint], capsys)

    out = tmp_path / "a.nir"
    rec = api.export(small_rsnn_checkpoint, output=out)
    assert out.is_file() and rec.format == "nir" and rec.report.output == str(out)
    from_cli = cli_json(["export", small_rsnn_checkpoint, "-o", tmp_path / "b.nir"], capsys)
    assert without(rec.as_dict(), "output") == without(from_cli, "output")
    assert text_of(rec).splitlines()[1:] == cli_text(["export", small_rsnn_checkpoint, "-o", tmp_path / "c.nir"],
                                                     capsys).splitlines()[1:]
    with pytest.raises(SnnccError, match="unknown export format"):
        api.export(small_rsnn_checkpoint, output=tmp_path / "d.onnx", to="onnx")


def test_import_notes_reach_the_record(tmp_path):
    """What the frontend noted in loading (here: all weights zero) is in ``notes`` as ``<file>: <note>``."""
    import torch

    from snncc.frontends.checkpoint import save_checkpoint
    from snncc.models import SNNConfig, SpikingClassifier

    model = SpikingClassifier(SNNConfig(n_hidden=8, n_outputs=28))
    with torch.no_grad():
        for p in model.parameters():
            p.zero_()
    path = tmp_path / "zero.pt"
    save_checkpoint(model, path, {"dt": 0.005})
    rec = api.inspect(path)
    assert len(rec.notes) == 1 and rec.notes[0].startswith("zero.pt: all weights are zero")
    assert api.export(path, output=tmp_path / "zero.nir").notes == rec.notes


@pytest.fixture(scope="module")
def synth_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("api_synth") / "set"
    rec = api.data_synth(out=d, repetitions=2, seed=4, thresholds=[1, 2])
    return d, rec


def test_data_synth(synth_dir, tmp_path, capsys):
    d, rec = synth_dir
    assert rec.samples == 54 and rec.files[-1] == "SYNTHETIC.json" and set(rec.mean_events_per_taxel) == {"1", "2"}
    from_cli = cli_json(["data", "synth", "-o", tmp_path / "s", "-n", "2", "--seed", "4", "--thresholds", "2,1"],
                        capsys)
    assert without(rec.as_dict(), "out") == without(from_cli, "out")
    for name in rec.files[:-1]:     # the same seed gives byte-identical files
        assert (d / name).read_bytes() == (tmp_path / "s" / name).read_bytes()
    assert text_of(rec).replace(str(d), "OUT") == cli_text(
        ["data", "synth", "-o", tmp_path / "t", "-n", "2", "--seed", "4", "--thresholds", "1,2"], capsys
    ).replace(str(tmp_path / "t"), "OUT")
    with pytest.raises(SnnccError, match="positive"):
        api.data_synth(out=tmp_path / "u", repetitions=1, thresholds="0")
    assert not (tmp_path / "u").exists()


def test_data_encode_and_frames(synth_dir, tmp_path, capsys):
    d, _ = synth_dir
    rec = api.data_encode(d, out=tmp_path / "e.npz", threshold=2, bin_ms=3, split_test=0.5)
    from_cli = cli_json(["data", "encode", d, "-t", "2", "-b", "3", "-o", tmp_path / "c.npz", "--split-test", "0.5"],
                        capsys)
    assert without(rec.as_dict(), "out") == without(from_cli, "out")
    assert rec.written == [str(tmp_path / f"e{s}.npz") for s in ("", "_train", "_test")]
    assert rec.encoded.inputs.shape == (54, 450, 24) and rec.encoded.meta["time_bin_size_ms"] == 3
    assert "merged" in text_of(rec)
    rec = api.data_frames(d, out=tmp_path / "f.npz")
    assert without(rec.as_dict(), "out") == without(cli_json(["data", "frames", d, "-o", tmp_path / "g.npz"], capsys),
                                                    "out")
    assert rec.encoded.inputs.dtype == np.float32 and text_of(rec).startswith("54 samples x 54 frames")
    with pytest.raises(SnnccError, match="^split_test: "):      # the keyword's name (the CLI says --split-test)
        api.data_frames(d, out=tmp_path / "h.npz", split_test=1.5)


def test_data_analyse_without_svms(synth_dir, capsys):
    d, _ = synth_dir
    options = dict(thresholds="1,2", svm=False, pca_step=0, event_svm=False)
    rec = api.data_analyse(d, **options)
    args = ["data", "analyse", d, "--thresholds", "1,2", "--no-svm", "--pca-step", "0", "--no-event-svm"]
    assert rec.as_dict() == cli_json(args, capsys)
    assert [r["threshold"] for r in rec.encoding] == [1.0, 2.0] and rec.synthetic and rec.figures == []
    assert text_of(rec) == cli_text(args, capsys)


def _events_set(path):
    from snncc.data.dataset_file import save_dataset

    rng = np.random.default_rng(0)
    labels = np.repeat(np.arange(27), 6)
    x = (rng.random((labels.size, 12, 24)) < 0.05).astype(np.uint8)
    for i, c in enumerate(labels):
        x[i, :, c % 24] = 1
    save_dataset(path, x, labels, {"kind": "events", "threshold": 1, "time_bin_size_ms": 5, "dt_s": 0.005,
                                   "synthetic": True, "source": "toy", "seed": 0})
    return path


def test_train_and_analyse_ttc(tmp_path, capsys):
    data = _events_set(tmp_path / "ev.npz")
    options = dict(data=data, epochs=1, seed=1, batch_size=64)
    rec = api.train("ffsnn", output=tmp_path / "a.pt", **options)
    from_cli = cli_json(["train", "ffsnn", "--data", data, "--epochs", "1", "--seed", "1", "--batch-size", "64",
                         "-o", tmp_path / "b.pt"], capsys)
    mine = rec.as_dict()
    for d in (mine, from_cli):
        d.pop("output")
        d["history"].pop("seconds")
        for e in d["epochs"]:
            e.pop("seconds")
    assert mine == from_cli and rec.output == str(tmp_path / "a.pt")
    text = text_of(rec)
    assert "ffsnn" in text and f"wrote {tmp_path / 'a.pt'}" in text
    with pytest.raises(SnnccError, match="KEY=VALUE"):
        api.train("ffsnn", output=tmp_path / "c.pt", overrides=["tau_mem"], **options)

    ttc = api.analyse_ttc([tmp_path / "a.pt"], data=[data], output=tmp_path / "ttc.json")
    assert ttc.as_dict() == json.loads((tmp_path / "ttc.json").read_text())
    assert ttc.as_dict() == cli_json(["analyse", "ttc", tmp_path / "a.pt", "--data", data], capsys)
    assert ttc.records[0].kind == "ffsnn" and text_of(ttc).endswith(f"wrote {tmp_path / 'ttc.json'}\n")
    with pytest.raises(SnnccError, match="figure"):
        api.analyse_ttc([tmp_path / "a.pt"], data=[data], figure=tmp_path / "x.gif")


def test_hpo_space_and_report_storage_rule(tmp_path, capsys):
    rec = api.hpo_space()
    assert rec.as_dict() == cli_json(["hpo", "space"], capsys)
    assert set(rec.space) == set(rec.as_dict()["paper_presets"]["1"])
    assert text_of(rec) == cli_text(["hpo", "space"], capsys)
    with pytest.raises(SnnccError, match="no study storage") as err:
        api.hpo_report("s", workdir=tmp_path)
    assert err.value.field == "--dir"

    from snncc.hpo.storage import report_command, study_storage_url

    assert study_storage_url("postgresql://u:p@h/db", tmp_path, must_exist=True) == "postgresql://u:p@h/db"
    assert study_storage_url(None, tmp_path) == f"sqlite:///{tmp_path.resolve() / 'hpo.sqlite3'}"
    assert report_command("s", "postgresql://u:secret@h/db", tmp_path) == "snncc hpo report s --storage 'postgresql://u:***@h/db'"
    assert report_command("s", None, tmp_path) == f"snncc hpo report s --dir {tmp_path}"


def test_hpo_run_and_report(tmp_path, capsys):
    """One tiny trial from Python, then its report from Python and from the CLI."""
    data = tmp_path / "braille"
    api.data_synth(out=data, repetitions=7, seed=5, thresholds="1")
    work = tmp_path / "w"
    from snncc.hpo.progress import StudyView

    class Seen(StudyView):   # the search's progress protocol, recorded
        def __init__(self):
            self.calls = []

        def __getattribute__(self, name):
            calls = object.__getattribute__(self, "calls")
            method = object.__getattribute__(self, name)
            if name == "calls" or not callable(method):
                return method
            return lambda *args: (calls.append(name), method(*args))[1]

    view = Seen()
    run = api.hpo_run("s", data=data, step="anneal", trials=1, epochs=1, hidden=8, ranges=["time_bin_size=10",
                      "nb_input_copies=1"], energy_samples=2, batch_size=64, startup=1, preset=False, workdir=work,
                      device="cpu", pruner="none", view=view)
    calls = view.calls
    assert calls[0] == "study_start" and calls[-1] == "close" and "study_update" in calls
    assert calls.index("trial_start") < calls.index("trial_epoch") < calls.index("trial_done")
    assert [s.study for s in run.summaries] == ["s"] and run.summaries[0].budget["complete"] == 1
    assert run.as_dict()[0]["study"] == "s" and run.report_command == f"snncc hpo report s --dir {work}"
    assert " ".join(text_of(run).split()).endswith(f"report: snncc hpo report s --dir {work}")
    rep = api.hpo_report("s", workdir=work, no_plot=True)
    assert rep.figure is None and rep.report.counts["complete"] == 1
    assert rep.as_dict() == cli_json(["hpo", "report", "s", "--dir", work, "--no-plot"], capsys)
    assert "Pareto" in text_of(rep)


class Calls:
    """A plain ``progress(done, total, phase)`` that records its calls."""

    def __init__(self):
        self.calls: list[tuple[int, int, str]] = []

    def __call__(self, done: int, total: int, phase: str) -> None:
        self.calls.append((done, total, phase))

    def check(self) -> list[tuple[int, int, str]]:
        """Some calls, 0 <= done <= total, ``done`` never falling while the phase stays; the calls."""
        assert self.calls
        for (d0, _, p0), (d1, _, p1) in zip(self.calls, self.calls[1:]):
            assert p0 != p1 or d1 >= d0, self.calls
        assert all(isinstance(p, str) and 0 <= d <= t for d, t, p in self.calls), self.calls
        return self.calls


def test_every_verb_taking_progress_reports_through_a_plain_callable(synth_dir, small_rsnn_checkpoint, tmp_path):
    """One convention: each verb's ``progress`` is ``progress(done, total, phase)``, and no verb needs rich."""
    import inspect

    taking = {name for name in api.__all__ if "progress" in inspect.signature(getattr(api, name)).parameters}
    assert taking == {"data_synth", "data_encode", "data_analyse", "train", "check", "emulate", "report", "bench",
                      "compile", "compare"}
    seen: dict[str, list] = {}

    p = Calls()
    api.data_synth(out=tmp_path / "s", repetitions=2, seed=4, thresholds=[1, 2], progress=p)
    seen["data_synth"] = p.check()
    assert p.calls[-1] == (27 * 2 + 3, 27 * 2 + 3, "encoding and writing")
    assert {c[2] for c in p.calls} == {"generating frames", "encoding and writing"}
    d, _ = synth_dir
    p = Calls()
    api.data_encode(d, out=tmp_path / "e.npz", threshold=1, bin_ms=5, progress=p)
    seen["data_encode"] = p.check()
    assert p.calls == [(0, 2, "loading / encoding"), (1, 2, "loading / encoding"), (2, 2, "loading / encoding")]
    p = Calls()
    api.data_analyse(d, thresholds="1,2", svm=False, pca_step=0, event_svm=False, progress=p)
    seen["data_analyse"] = p.check()
    assert [d for d, _, _ in p.calls] == sorted(d for d, _, _ in p.calls) and p.calls[-1][0] == p.calls[-1][1] == 4

    p, epochs = Calls(), []
    api.train("ffsnn", data=_events_set(tmp_path / "ev.npz"), output=tmp_path / "f.pt", epochs=2, seed=1,
              batch_size=64, progress=p, on_epoch=epochs.append)
    seen["train"] = p.check()
    assert p.calls == [(k, 6, f"epoch {1 + (k - 1) // 3}/2") for k in range(1, 7)]   # 162 samples: 3 batches
    assert [e.epoch for e in epochs] == [1, 2]

    x = (np.random.default_rng(3).random((3, 20, 24)) < 0.1).astype(np.uint8)
    np.savez(tmp_path / "d.npz", inputs=x, labels=np.array([0, 1, 2], np.int64))
    p = Calls()
    api.check(small_rsnn_checkpoint, target="loihi", data=tmp_path / "d.npz", progress=p)
    seen["check"] = p.check()
    p = Calls()
    api.compile(small_rsnn_checkpoint, target="loihi", output=tmp_path / "m.net", progress=p)
    assert p.check()[-1] == (1, 1, "validating the bundle against the IR reference")
    seen["compile"] = p.calls
    np.save(tmp_path / "x.npy", np.tile(x, (1, 1, 2)))
    p = Calls()
    api.emulate(tmp_path / "m.net", input=tmp_path / "x.npy", output=tmp_path / "o.npz", progress=p)
    seen["emulate"] = p.check()
    p = Calls()
    api.report(tmp_path / "m.net", energy=True, samples=2, progress=p)
    seen["report"] = p.check()
    p = Calls()
    api.compile(small_rsnn_checkpoint, target="jetson", output=tmp_path / "j", time_steps=20, progress=p)
    assert [c[2] for c in p.check()] == ["exporting the ONNX models"] * 3 + [
        "validating in ONNX Runtime against the IR reference"] * 2
    p = Calls()
    api.bench(tmp_path / "j", samples=2, repeats=1, warmup_passes=1, timed_passes=1, progress=p)
    seen["bench"] = p.check()
    p = Calls()
    api.compare(small_rsnn_checkpoint, targets="jetson", samples=3, time_steps=20, progress=p)
    seen["compare"] = p.check()
    assert {c[2] for c in seen["compare"]} >= {"the float graph", "jetson: compiling", "jetson: measuring agreement"}
    assert set(seen) == taking
    for name in ("check", "emulate", "report"):
        assert seen[name][-1][0] == seen[name][-1][1], (name, seen[name])
