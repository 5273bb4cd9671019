#!/usr/bin/env python
"""The paper's whole pipeline on the SYNTHETIC Braille set, through snncc's Python API.

    python examples/braille/run_pipeline.py                # small settings: a few minutes on 2 CPU cores
    python examples/braille/run_pipeline.py --full         # the paper's settings (300 epochs: days on a CPU)
    python examples/braille/run_pipeline.py --baselines    # + FCN, ResNet, Encoder, TCNN, Inception, TTC, latency

Steps: generate (snncc.api.data_synth) -> encode (events th 1 at 5 ms, frames: data_encode,
data_frames) -> train RSNN th1, LSTM, eLSTM (snncc.api.train) -> quantization-aware fine-tuning of the
RSNN -> compile for Loihi and Jetson (snncc.api.compile) -> measure what each target loses (check)
-> the RSNN's core map (snncc.api.map) and its energy and delay ESTIMATE (snncc.api.report) -> a
results table beside the paper's numbers (results.md and results.json in the output directory)
and figures (figures/*.png, linked from results.md: training curves, accuracy per model and
deployment, the core map, energy and delay beside the paper's measurement). Long steps print
progress: a line per training epoch, and while a step runs a live count on a terminal (a line
every PROGRESS_EVERY_S seconds when stdout is not one). ``--baselines`` adds the time-series classifiers (train, compile for Jetson), time to
classification of every model (snncc.api.analyse_ttc, ttc.png) and their batch-1 Jetson-artefact
latency in one bench run. Every step runs in this process through ``snncc.api`` (each record is
the ``--json`` output of the same ``snncc`` command; docs/api.md shows the pairs).

A step that fails is reported as failed with its error line, and the steps that need it as
skipped; nothing is faked. The data are synthetic, so the numbers are not the paper's and are
labelled so.
"""

from __future__ import annotations

import argparse
import inspect
import json
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))   # pipeline_figures.py beside this file
import pipeline_figures  # noqa: E402

PAPER = {  # real data, the paper's figures (accuracy, %)
    "rsnn_th1_pytorch": 79.90,
    "rsnn_th1_loihi": 78.32,
    "lstm_frames": 96.92,
    "elstm_events": 82.31,
}
PAPER_LOIHI = {"cores": 8, "power_mw": 31.0, "energy_uj_per_sample": 71.0, "delay_ms_per_sample": 2.3}  # measured
PAPER_JETSON_LSTM = {"power_mw": 5385.0, "energy_uj_per_sample": 35212.0, "delay_ms_per_sample": 6.7}   # measured
PAPER_ENERGY_RATIO = 496          # the paper's Table: LSTM on Jetson / RSNN on Loihi, energy per sample (both measured)
PAPER_BASELINES = {  # kind -> (label, test accuracy %, trainable parameters as the paper states them)
    "resnet": ("ResNet", 98.2, "516k"),
    "inception": ("Inception", 97.8, "452k"),
    "fcn": ("FCN", 97.7, "280k"),
    "encoder": ("Encoder", 93.9, "~10x FCN"),
    "tcnn": ("TCNN", 83.4, "2,673"),
}

SMALL = {"repetitions": 40, "rsnn_epochs": 3, "lstm_epochs": 15, "elstm_epochs": 3, "qat_epochs": 1}
FULL = {"repetitions": 200, "rsnn_epochs": 300, "lstm_epochs": 300, "elstm_epochs": 300, "qat_epochs": 10}
BASELINE_SMALL = {"baseline_epochs": 5}
BASELINE_FULL = {"baseline_epochs": 300}
ENERGY_SAMPLES = 64            # test samples emulated for the energy and delay ESTIMATE
PROGRESS_EVERY_S = 15.0        # stdout not a terminal: at most one progress line per step this often
FIGURES = "figures"            # the figures' folder inside --out


class StepProgress:
    """What a long step shows while it runs. ``on_epoch(record)``: one line per training epoch, as
    ``snncc train`` prints it. ``progress(done, total, phase)``: on a terminal a count rewritten in
    place; otherwise a line at most every ``PROGRESS_EVERY_S`` seconds."""

    def __init__(self, name: str, stream=None, every_s: float | None = None):
        self.name, self.stream = name, stream or sys.stdout
        self.every_s = PROGRESS_EVERY_S if every_s is None else every_s
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.last_line = time.monotonic()
        self.live = False

    def _line(self, text: str) -> None:
        if self.live:
            self.stream.write("\r\033[K")
            self.live = False
        self.stream.write(f"       {self.name}: {text}\n")
        self.stream.flush()

    def progress(self, done: int, total: int, phase: str = "") -> None:
        text = f"{phase} {done}/{total}".strip()
        if self.tty:
            self.stream.write(f"\r\033[K       {self.name}: {text}")
            self.stream.flush()
            self.live = True
        elif time.monotonic() - self.last_line >= self.every_s:
            self._line(text)
            self.last_line = time.monotonic()

    def on_epoch(self, record) -> None:
        val = record.val_accuracy
        self._line(f"epoch {record.epoch}: loss {record.loss:.4f}  train {100 * record.train_accuracy:.2f} %  "
                   f"test {100 * record.test_accuracy:.2f} %" + (f"  val {100 * val:.2f} %" if val is not None else "")
                   + f"  ({record.seconds:.1f} s)")
        self.last_line = time.monotonic()

    def close(self) -> None:
        if self.live:
            self.stream.write("\r\033[K")
            self.stream.flush()
            self.live = False


@dataclass
class Step:
    name: str
    argv: list[str]
    status: str = "pending"          # ok | failed | skipped
    seconds: float = 0.0
    message: str = ""
    record: dict | None = None


@dataclass
class Pipeline:
    out: Path
    settings: dict
    seed: int
    device: str = "auto"       # where every training step runs: auto (CUDA when available) | cpu | cuda[:N]
    steps: list[Step] = field(default_factory=list)

    def skipped(self, step: Step, needs: tuple[str, ...]) -> bool:
        """Mark ``step`` skipped (and say so) when a step it needs did not succeed."""
        blocked = [n for n in needs if self.status(n) != "ok"]
        if blocked:
            step.status, step.message = "skipped", f"needs {', '.join(blocked)}"
            print(f"[skip] {step.name}: {step.message}", flush=True)
        return bool(blocked)

    def api(self, name: str, verb: str, *args, needs: tuple[str, ...] = (), **options) -> Step:
        """Call ``snncc.api.<verb>(*args, **options)`` in this process; its ``as_dict()`` is the record.

        An snncc error is the same ``snncc: error: ...`` line the command prints; any other error is
        a failed step with its type and message.
        """
        import snncc.api
        from snncc.errors import SnnccError
        from snncc.records import to_jsonable

        def text(v) -> str:
            return f"[{', '.join(map(str, v))}]" if isinstance(v, list) else str(v)

        shown = [text(a) for a in args] + [f"{k}={text(v)}" for k, v in options.items()]
        step = Step(name, [f"snncc.api.{verb}", *shown])
        self.steps.append(step)
        if self.skipped(step, needs):
            return step
        print(f"[run ] {name}: snncc.api.{verb}({', '.join(shown)})", flush=True)
        function = getattr(snncc.api, verb)
        accepts = inspect.signature(function).parameters
        shows = StepProgress(name)
        hooks = {k: v for k, v in (("progress", shows.progress), ("on_epoch", shows.on_epoch)) if k in accepts}
        started = time.perf_counter()
        try:
            step.record = to_jsonable(function(*args, **options, **hooks).as_dict())
            step.status = "ok"
        except SnnccError as err:
            step.message = f"snncc: error: {err.line()}"
            step.status = "failed"
        except Exception as ex:  # reported in the table, never hidden
            step.status, step.message = "failed", f"{type(ex).__name__}: {ex}"
        finally:
            shows.close()
        step.seconds = round(time.perf_counter() - started, 1)
        print(f"[{step.status:>4}] {name} ({step.seconds} s){': ' + step.message if step.message else ''}", flush=True)
        return step

    def python(self, name: str, func, *args, needs: tuple[str, ...] = ()) -> Step:
        """A step done in this process (no snncc verb for it); an error is a failed step."""
        step = Step(name, [func.__name__, *map(str, args)])
        self.steps.append(step)
        if self.skipped(step, needs):
            return step
        started = time.perf_counter()
        try:
            func(*args)
            step.status = "ok"
        except Exception as ex:  # reported in the table, never hidden
            step.status, step.message = "failed", f"{type(ex).__name__}: {ex}"
        step.seconds = round(time.perf_counter() - started, 1)
        print(f"[{step.status:>4}] {name} ({step.seconds} s){': ' + step.message if step.message else ''}", flush=True)
        return step

    def status(self, name: str) -> str:
        return next((s.status for s in self.steps if s.name == name), "missing")

    def record(self, name: str) -> dict | None:
        return next((s.record for s in self.steps if s.name == name and s.status == "ok"), None)


def write_test_split(checkpoint: Path, encoded: Path, dest: Path) -> None:
    """The test samples of a trained checkpoint's own split, as a data-set file for snncc check."""
    import torch

    from snncc.data.dataset_file import load_dataset, save_dataset
    from snncc.training.pipeline import assigned

    meta_ckpt = torch.load(checkpoint, weights_only=True)["metadata"]
    test = assigned(meta_ckpt["split_assignment"], "test")
    inputs, labels, meta = load_dataset(encoded)
    save_dataset(dest, inputs[test], labels[test], dict(meta, source=f"{meta.get('source')} (test split of {checkpoint.name})"))


def baselines(p: Pipeline, out: Path, frames: Path, events: Path, seed: str) -> None:
    """Train and compile the time-series classifiers; TTC of every trained model; one latency run."""
    for kind in PAPER_BASELINES:
        p.api(f"train {kind}", "train", kind, data=frames, epochs=p.settings["baseline_epochs"],
              output=out / f"{kind}.pt", seed=int(seed), device=p.device, needs=("encode frames",))
        p.api(f"compile {kind} Jetson", "compile", out / f"{kind}.pt", target="jetson", output=out / f"{kind}_jetson",
              needs=(f"train {kind}",))
    trained = [(name, ckpt) for name, ckpt in (("train RSNN th1", "rsnn_th1.pt"), ("train LSTM", "lstm.pt"),
                                               ("train eLSTM", "elstm.pt"))
               + tuple((f"train {k}", f"{k}.pt") for k in PAPER_BASELINES) if p.status(name) == "ok"]
    if trained:
        p.api("TTC", "analyse_ttc", [out / c for _, c in trained], data=[frames, events], figure=out / "ttc.png",
              output=out / "ttc.json", needs=tuple(n for n, _ in trained))
    compiled = [(name, art) for name, art in (("compile RSNN Jetson", "rsnn_th1_jetson"),
                                              ("compile LSTM Jetson", "lstm_jetson"))
                + tuple((f"compile {k} Jetson", f"{k}_jetson") for k in PAPER_BASELINES) if p.status(name) == "ok"]
    if compiled:
        p.api("bench Jetson artefacts", "bench", [out / a for _, a in compiled], samples=32, repeats=3,
              warmup_passes=1, timed_passes=2, needs=tuple(n for n, _ in compiled))


def inputs_kind(data_label: str) -> str:
    """What a bench record timed: SYNTHETIC random inputs (no data set fitted) or a data set."""
    if data_label.upper().startswith("SYNTHETIC"):
        return "SYNTHETIC (random)"
    return "data set (SYNTHETIC)" if "synthetic" in data_label.lower() else "data set"


def pct(x) -> str:
    return "—" if x is None else f"{x:.2f} %"


def percent(x) -> float | None:
    return None if x is None else round(100 * x, 2)


def results(p: Pipeline) -> dict:
    def train_acc(name):
        r = p.record(name)
        return None if r is None else r["history"]["test_accuracy"]

    def check_acc(name, key):
        return stage_accuracy(p.record(name), key)

    qat = p.record("train RSNN QAT")
    rows = [
        {"model": "RSNN th1, float (PyTorch, authors' order)", "ours_percent": percent(train_acc("train RSNN th1")), "paper_percent": PAPER["rsnn_th1_pytorch"]},
        {"model": "RSNN th1, Loihi emulated (bit-exact, global scale)", "ours_percent": percent(check_acc("check RSNN Loihi", "artefact")), "paper_percent": PAPER["rsnn_th1_loihi"]},
        {"model": "RSNN th1, fake-quantized after QAT", "ours_percent": percent(None if qat is None else qat["quantization"]["after"]["quantized_test_accuracy"]), "paper_percent": None},
        {"model": "RSNN th1 after QAT, Loihi emulated", "ours_percent": percent(check_acc("check RSNN QAT Loihi", "artefact")), "paper_percent": None},
        {"model": "RSNN th1, Jetson (ONNX Runtime)", "ours_percent": percent(check_acc("check RSNN Jetson", "artefact")), "paper_percent": None},
        {"model": "LSTM on frames", "ours_percent": percent(train_acc("train LSTM")), "paper_percent": PAPER["lstm_frames"]},
        {"model": "LSTM, Jetson (ONNX Runtime)", "ours_percent": percent(check_acc("check LSTM Jetson", "artefact")), "paper_percent": None},
        {"model": "eLSTM on events th1", "ours_percent": percent(train_acc("train eLSTM")), "paper_percent": PAPER["elstm_events"]},
    ]
    for kind, (label, paper_acc, paper_params) in PAPER_BASELINES.items():
        r = p.record(f"train {kind}")
        if p.status(f"train {kind}") == "missing":
            continue
        params = "?" if r is None else f"{r['parameters']:,}"
        rows.append({"model": f"{label} on frames ({params} params; paper {paper_params})",
                     "ours_percent": percent(train_acc(f"train {kind}")), "paper_percent": paper_acc})
    extra = {}
    ttc = p.record("TTC")
    if ttc is not None:
        extra["ttc"] = [{k: m[k] for k in ("model", "kind", "method", "final_accuracy", "mean_ttc", "median_ttc",
                                          "never_correct_share", "samples")} for m in ttc["models"]]
    bench = p.record("bench Jetson artefacts")
    if bench is not None:
        extra["latency"] = [{**{k: m[k] for k in ("artefact", "kind", "median_ms", "spread_ms", "ratio_to_reference")},
                             "inputs": inputs_kind(m.get("data", ""))} for m in bench["models"]]
    return {
        **extra,
        "paper_comparison": paper_comparison(p),
        "accuracy_by_model": accuracy_by_model(p),
        "training_curves": training_curves(p),
        "loihi": loihi_figures(p),
        "learning": learning(p.record("train RSNN th1"), p.settings),
        "data": "SYNTHETIC Braille set (snncc data synth), NOT the paper's recordings: compare trends, not values",
        "settings": p.settings,
        "training_device": trained_on(p),
        "selection": "training accuracies are of the best TEST epoch, as the authors selected (optimistic)",
        "rows": rows,
        "steps": [asdict(s) | {"record": None} for s in p.steps],
    }


def compare_row(record: dict | None, target: str) -> dict | None:
    """The row of ``target`` in a ``snncc compare`` record (None when absent)."""
    return next((r for r in (record or {}).get("rows") or [] if r.get("target") == target), None)


def paper_comparison(p: Pipeline) -> dict:
    """The paper's headline (RSNN on Loihi against the LSTM on Jetson) as measured here: accuracies on this run's
    SYNTHETIC test splits, the RSNN's energy per sample on Loihi as snncc's ESTIMATE against the LSTM's on the Jetson
    as the paper MEASURED it (no Jetson here), and their ratio beside the paper's (both measured there)."""
    rsnn = compare_row(p.record("compare RSNN"), "loihi")
    lstm = compare_row(p.record("compare LSTM"), "jetson")
    energy = None if rsnn is None or not rsnn.get("energy") else rsnn["energy"]["uj_per_sample"]
    return {"rsnn_loihi_accuracy": None if rsnn is None else rsnn.get("accuracy"),
            "lstm_jetson_accuracy": None if lstm is None else lstm.get("accuracy"),
            "paper_rsnn_loihi_accuracy": PAPER["rsnn_th1_loihi"], "paper_lstm_jetson_accuracy": PAPER["lstm_frames"],
            "rsnn_loihi_energy_uj_estimate": energy,
            "energy_source": None if rsnn is None or not rsnn.get("energy") else rsnn["energy"]["source"],
            "lstm_jetson_energy_uj_paper": PAPER_JETSON_LSTM["energy_uj_per_sample"],
            "ratio": None if not energy else PAPER_JETSON_LSTM["energy_uj_per_sample"] / energy,
            "paper_ratio": PAPER_ENERGY_RATIO}


def stage_accuracy(record: dict | None, key: str) -> float | None:
    """A check record's accuracy (``snncc check --json``: the kit's CheckReport): ``"float"`` or ``"artefact"``, or a
    stage the target names (Loihi: ``ir_quantized``, ``emulator``, ... in ``details.accuracy_by_stage``)."""
    if record is None:
        return None
    overall = record.get("accuracy") or {}
    if key in overall:
        return overall[key]
    by_stage = (record.get("details") or {}).get("accuracy_by_stage") or {}
    if key in by_stage:
        return by_stage[key]
    return next((s.get("accuracy") for s in record.get("stages") or [] if s.get("key") == key), None)


CHANCE_PERCENT = 100.0 / 27
TRAINED = (("train RSNN th1", "RSNN th1"), ("train RSNN QAT", "RSNN th1 QAT"), ("train LSTM", "LSTM"),
           ("train eLSTM", "eLSTM"))


def accuracy_by_model(p: Pipeline) -> list[dict]:
    """Per model, test accuracy (%) in float, quantized (Loihi weights in float), on the bit-exact Loihi
    emulator and as the Jetson artefact in ONNX Runtime, beside the paper's figures (real data)."""
    def acc(step, *keys):
        if keys and keys[0] == "accuracy":           # a check record: its overall or a stage's accuracy
            return percent(stage_accuracy(p.record(step), keys[1]))
        r = p.record(step)
        for key in keys:
            r = None if r is None else r.get(key)
        return percent(r)

    def row(model, float_, quantized=None, emulated=None, jetson=None, paper_float=None, paper_loihi=None):
        return {"model": model, "float": float_, "quantized": quantized, "loihi_emulated": emulated,
                "jetson": jetson, "paper_float": paper_float, "paper_loihi": paper_loihi}

    rows = [
        row("RSNN th1", acc("check RSNN Loihi", "accuracy", "float") or acc("train RSNN th1", "history",
                                                                             "test_accuracy"),
            acc("check RSNN Loihi", "accuracy", "ir_quantized"), acc("check RSNN Loihi", "accuracy", "artefact"),
            acc("check RSNN Jetson", "accuracy", "artefact"), PAPER["rsnn_th1_pytorch"], PAPER["rsnn_th1_loihi"]),
        row("RSNN th1 after QAT", acc("check RSNN QAT Loihi", "accuracy", "float"),
            acc("check RSNN QAT Loihi", "accuracy", "ir_quantized"), acc("check RSNN QAT Loihi", "accuracy", "artefact")),
        row("LSTM (frames)", acc("train LSTM", "history", "test_accuracy"), jetson=acc("check LSTM Jetson", "accuracy",
                                                                                        "artefact"),
            paper_float=PAPER["lstm_frames"]),
        row("eLSTM (events th1)", acc("train eLSTM", "history", "test_accuracy"), paper_float=PAPER["elstm_events"]),
    ]
    for kind, (label, paper_acc, _) in PAPER_BASELINES.items():
        if p.status(f"train {kind}") != "missing":
            rows.append(row(label, acc(f"train {kind}", "history", "test_accuracy"), paper_float=paper_acc))
    return rows


def training_curves(p: Pipeline) -> list[dict]:
    """Per model trained in this run: loss and accuracies per epoch (the train records' ``epochs``)."""
    names = TRAINED + tuple((f"train {k}", label) for k, (label, _, _) in PAPER_BASELINES.items())
    curves = []
    for step, label in names:
        r = p.record(step)
        if r and r.get("epochs"):
            curves.append({"model": label, "epochs": [{k: e.get(k) for k in ("epoch", "loss", "train_accuracy",
                                                                             "test_accuracy")} for e in r["epochs"]]})
    return curves


def loihi_figures(p: Pipeline) -> dict:
    """The RSNN's core map (cores, chips) and its energy and delay per sample: an ESTIMATE beside the
    paper's measurement."""
    mapped, energy = p.record("map RSNN Loihi"), p.record("energy RSNN Loihi")
    out: dict = {}
    if mapped:
        out["core_map"] = {"cores": mapped["n_cores"], "chips": mapped["n_chips"], "lower_bound": mapped["lower_bound"],
                           "paper_cores": PAPER_LOIHI["cores"]}
    if energy:
        est = energy["estimate"]
        out["estimate"] = {"label": est["label"], "inputs": est["inputs"], "samples": est["samples"],
                           "cores": est["n_cores"], "energy_uj_per_sample": est["energy_uj_per_sample"]["total"],
                           "delay_ms_per_sample": est["delay_ms_per_sample"],
                           "dynamic_power_mw": est["dynamic_power_mw"], "paper_measurement": est["paper_measurement"]}
    return out


def trained_on(p: Pipeline) -> str:
    """Where the training steps ran (each train record says), else what was asked for."""
    ran = sorted({r["device"] for s in p.steps if s.name.startswith("train ") and (r := p.record(s.name))
                  and r.get("device")})
    return ", ".join(ran) if ran else f"{p.device} (asked; no training step ran)"


def learning(record: dict | None, settings: dict) -> dict:
    """What the (small) RSNN reached: test accuracy per epoch against chance (1 in 27 letters)."""
    if not record or not record.get("epochs"):
        return {"rsnn_test_percent_per_epoch": [], "statement": "the RSNN was not trained in this run"}
    accs = [round(100 * e["test_accuracy"], 2) for e in record["epochs"]]
    best = max(accs)
    verdict = ("it is learning: above chance" if best > 2 * CHANCE_PERCENT
               else "NOT clearly above chance: more epochs or data needed")
    statement = (f"RSNN th1 ({settings.get('repetitions')} repetitions per letter, {len(accs)} epochs): test accuracy "
                 f"{' -> '.join(f'{a:.1f} %' for a in accs)} (chance {CHANCE_PERCENT:.1f} %); {verdict}. "
                 "Far from converged at these settings; the paper's schedule is --full.")
    return {"rsnn_test_percent_per_epoch": accs, "chance_percent": round(CHANCE_PERCENT, 2), "statement": statement}


def paper_comparison_markdown(c: dict) -> list[str]:
    """The paper's Table of Loihi against Jetson, beside this run (``paper_comparison``)."""
    if not c or (c.get("rsnn_loihi_accuracy") is None and c.get("lstm_jetson_accuracy") is None):
        return []
    energy, ratio = c.get("rsnn_loihi_energy_uj_estimate"), c.get("ratio")
    return ["", "The paper's comparison, RSNN th1 on Loihi against the LSTM on Jetson, as measured here (this run: "
            "SYNTHETIC test splits, snncc compare; the full cross-platform tables are compare_rsnn.md and "
            "compare_lstm.md):", "",
            "| | RSNN th1 on Loihi | LSTM on Jetson | LSTM / RSNN |", "|---|---|---|---|",
            f"| accuracy, this run | {pct(percent(c.get('rsnn_loihi_accuracy')))} (bit-exact emulator) | "
            f"{pct(percent(c.get('lstm_jetson_accuracy')))} (ONNX Runtime) | |",
            f"| accuracy, paper (real data) | {c['paper_rsnn_loihi_accuracy']:.2f} % | "
            f"{c['paper_lstm_jetson_accuracy']:.2f} % | |",
            f"| energy per sample | {'—' if energy is None else f'{energy:.3g} uJ (snncc ESTIMATE)'} | "
            f"{c['lstm_jetson_energy_uj_paper']:,.0f} uJ (the paper's MEASUREMENT; no Jetson here) | "
            f"{'—' if ratio is None else f'{ratio:,.0f}x (ESTIMATE against measurement)'} |",
            f"| energy per sample, paper (both measured) | 71 uJ | 35,212 uJ | {c['paper_ratio']}x |", "",
            f"Energy source for the Loihi ESTIMATE: {c.get('energy_source') or '—'}."]


def figures_markdown(res: dict) -> list[str]:
    """The accuracy-per-deployment table, the Loihi ESTIMATE beside the paper's measurement, and the figures."""
    lines = []
    by_model = [m for m in res.get("accuracy_by_model", []) if any(m[k] is not None for k in
                                                                  ("float", "quantized", "loihi_emulated", "jetson"))]
    if by_model:
        lines += ["", "Test accuracy per model and deployment (this run: SYNTHETIC data; paper: real recordings):", "",
                  "| model | float | quantized | Loihi emulated | Jetson (ONNX Runtime) | paper, PyTorch | paper, Loihi |",
                  "|---|---|---|---|---|---|---|"]
        for m in by_model:
            lines.append(f"| {m['model']} | " + " | ".join(pct(m[k]) for k in ("float", "quantized", "loihi_emulated",
                                                                          "jetson", "paper_float", "paper_loihi")) + " |")
    loihi = res.get("loihi", {})
    est, cmap = loihi.get("estimate"), loihi.get("core_map")
    if est or cmap:
        paper = PAPER_LOIHI
        lines += ["", "Loihi 1, RSNN th1 per sample: snncc's ESTIMATE (Davies 2018 Table 2, dynamic energy only; not a "
                  "measurement) beside the paper's MEASUREMENT on the chip:", "",
                  "| | snncc ESTIMATE (this bundle) | paper, measured |", "|---|---|---|"]
        if cmap:
            lines.append(f"| cores | {cmap['cores']} (lower bound {cmap['lower_bound']}) | {paper['cores']} |")
        if est:
            lines += [f"| energy per sample | {est['energy_uj_per_sample']:.1f} uJ | {paper['energy_uj_per_sample']:g} uJ |",
                      f"| delay per sample | {est['delay_ms_per_sample']:.2f} ms | {paper['delay_ms_per_sample']:g} ms |",
                      f"| power | {est['dynamic_power_mw']:.1f} mW (dynamic only) | {paper['power_mw']:g} mW (total) |",
                      "", f"ESTIMATE inputs: {est['inputs']}, {est['samples']} samples (SYNTHETIC data)."]
    if res.get("figures"):
        lines += ["", "## Figures", ""]
        for name, (path, caption) in res["figures"].items():
            lines += [f"![{caption}]({path})", "", f"*{caption}* (`{path}`)", ""]
    return lines


def write_figures(p: Pipeline, res: dict) -> dict[str, tuple[str, str]]:
    """Draw the figures into ``<out>/figures`` (a failed figure is a failed step, never hidden); name ->
    (path relative to ``out``, caption) of those written, the core map included when its step ran."""
    folder = p.out / FIGURES
    drawn: dict[str, tuple[str, str]] = {}
    captions = {
        "training_curves": "Training curves: loss and accuracy per epoch of every model trained (SYNTHETIC data)",
        "accuracy": "Accuracy per model: float, quantized, Loihi emulated, Jetson, beside the paper's figures (paper: "
                    "real data; this run: SYNTHETIC)",
        "core_map": "Core map of the RSNN th1 bundle: utilisation of each Loihi core",
        "energy_delay": "Loihi energy and delay per sample and cores: snncc's ESTIMATE beside the paper's measurement",
    }

    def figure(name: str, func, *args) -> None:
        def draw() -> None:
            path = func(*args, folder / f"{name}.png")
            if path is not None:
                drawn[name] = (f"{FIGURES}/{path.name}", captions[name])

        draw.__name__ = f"pipeline_figures.{func.__name__}"
        p.python(f"figure {name}", draw)

    figure("training_curves", pipeline_figures.training_curves, res["training_curves"], CHANCE_PERCENT)
    figure("accuracy", pipeline_figures.accuracy, res["accuracy_by_model"])
    if p.status("map RSNN Loihi") == "ok" and (folder / "core_map.png").is_file():   # drawn by snncc.api.map
        drawn["core_map"] = (f"{FIGURES}/core_map.png", captions["core_map"])
    figure("energy_delay", pipeline_figures.energy_delay, res["loihi"].get("estimate"))
    return dict(sorted(drawn.items(), key=lambda kv: list(captions).index(kv[0])))


def markdown(res: dict) -> str:
    lines = ["# Braille pipeline results (SYNTHETIC data)", "", f"> {res['data']}.", f"> {res['selection']}.", "",
             f"Settings: {json.dumps(res['settings'])}; trained on: {res.get('training_device', '?')}", "",
             f"Small-run check: {res.get('learning', {}).get('statement', '')}", "",
             "| model | this run (synthetic) | paper (real data) |", "|---|---|---|"]
    for r in res["rows"]:
        lines.append(f"| {r['model']} | {pct(r['ours_percent'])} | {pct(r['paper_percent'])} |")
    if res.get("ttc"):
        lines += ["", "Time to classification (share of the signal after which the prediction is right for good; "
                  "mean over the test samples classified right at the end; buffered classifiers: zero-padded "
                  "truncated input):", "", "| model | kind | accuracy | mean TTC | median TTC | no TTC |",
                  "|---|---|---|---|---|---|"]
        for m in res["ttc"]:
            f = lambda v: "—" if v is None else f"{v:.3f}"  # noqa: E731
            lines.append(f"| {m['model']} | {m['kind']} | {100 * m['final_accuracy']:.1f} % | {f(m['mean_ttc'])} | "
                         f"{f(m['median_ttc'])} | {100 * m['never_correct_share']:.1f} % |")
    if res.get("latency"):
        lines += ["", "Jetson artefacts, batch-1 latency in ONNX Runtime on THIS machine's CPU (not a Jetson; "
                  "noisy on a shared machine), ratios to the first:", "",
                  "| artefact | kind | inputs | median ms | spread ms | x first |", "|---|---|---|---|---|---|"]
        for m in res["latency"]:
            lines.append(f"| {Path(m['artefact']).name} | {m['kind']} | {m.get('inputs', '?')} | {m['median_ms']:.3f} | "
                         f"{m['spread_ms']:.3f} | {m['ratio_to_reference']:.2f} |")
    lines += paper_comparison_markdown(res.get("paper_comparison") or {})
    lines += figures_markdown(res)
    lines += ["", "| step | status | seconds | message |", "|---|---|---|---|"]
    for s in res["steps"]:
        lines.append(f"| {s['name']} | {s['status']} | {s['seconds']} | {s['message'].replace('|', '/')} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--full", action="store_true", help="the paper's settings (200 repetitions, 300 epochs)")
    ap.add_argument("--out", type=Path, default=Path("braille_run"), help="output directory (default ./braille_run)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--baselines", action="store_true",
                    help="also train and compile FCN, ResNet, Encoder, TCNN, Inception; TTC of every model; latency")
    ap.add_argument("--device", default="auto",
                    help="where training runs: auto (CUDA when available, else the CPU), cpu, cuda or cuda:N")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=N",
                    help=f"override one setting ({', '.join(SMALL)}), e.g. --set rsnn_epochs=5")
    args = ap.parse_args(argv)
    from snncc.errors import SnnccError
    from snncc.training.device import resolve_device

    try:
        resolve_device(args.device)          # a bad or absent device stops here, before any step runs
    except SnnccError as ex:
        ap.error(ex.line())
    settings = dict(FULL if args.full else SMALL)
    if args.baselines:
        settings.update(BASELINE_FULL if args.full else BASELINE_SMALL)
    for item in args.set:
        key, _, value = item.partition("=")
        if key not in settings or not value.isdigit() or int(value) < 1:
            ap.error(f"--set {item}: expected KEY=N with KEY one of {', '.join(settings)} and N >= 1")
        settings[key] = int(value)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    p = Pipeline(out, settings, args.seed, device=args.device)
    data, events, frames = out / "data", out / "events_th1.npz", out / "frames.npz"
    seed = str(args.seed)
    s = settings

    p.api("generate", "data_synth", out=data, repetitions=s["repetitions"], seed=args.seed, thresholds="1")
    p.api("encode events", "data_encode", data, threshold=1, bin_ms=5, out=events, needs=("generate",))
    p.api("encode frames", "data_frames", data, out=frames, needs=("generate",))
    p.api("train RSNN th1", "train", "rsnn", threshold=1, data=events, epochs=s["rsnn_epochs"],
          output=out / "rsnn_th1.pt", seed=args.seed, device=p.device, needs=("encode events",))
    p.api("train RSNN QAT", "train", "rsnn", data=events, qat_from=out / "rsnn_th1.pt", qat_epochs=s["qat_epochs"],
          output=out / "rsnn_th1_qat.pt", seed=args.seed, device=p.device, needs=("train RSNN th1",))
    p.api("train LSTM", "train", "lstm", data=frames, epochs=s["lstm_epochs"], output=out / "lstm.pt", seed=args.seed,
          device=p.device, needs=("encode frames",))
    p.api("train eLSTM", "train", "elstm", threshold=1, data=events, epochs=s["elstm_epochs"], output=out / "elstm.pt",
          seed=args.seed, device=p.device, needs=("encode events",))

    for name, model, target, artefact, needs in (
        ("compile RSNN Loihi", "rsnn_th1.pt", "loihi", "rsnn_th1.net", "train RSNN th1"),
        ("compile RSNN QAT Loihi", "rsnn_th1_qat.pt", "loihi", "rsnn_th1_qat.net", "train RSNN QAT"),
        ("compile RSNN Jetson", "rsnn_th1.pt", "jetson", "rsnn_th1_jetson", "train RSNN th1"),
        ("compile LSTM Jetson", "lstm.pt", "jetson", "lstm_jetson", "train LSTM"),
    ):
        scale = {"scale": "global"} if target == "loihi" else {}
        p.api(name, "compile", out / model, target=target, output=out / artefact, **scale, needs=(needs,))

    # snncc check on each model's own test split (the samples it was not trained on)
    for ckpt, encoded, name, needs in ((out / "rsnn_th1.pt", events, "rsnn_test.npz", "train RSNN th1"),
                                       (out / "lstm.pt", frames, "lstm_test.npz", "train LSTM")):
        p.python(f"test split {name}", write_test_split, ckpt, encoded, out / name, needs=(needs,))
    for name, model, artefact, test, needs in (     # the artefacts compile wrote, measured again
        ("check RSNN Loihi", "rsnn_th1.pt", "rsnn_th1.net", "rsnn_test.npz", "compile RSNN Loihi"),
        ("check RSNN QAT Loihi", "rsnn_th1_qat.pt", "rsnn_th1_qat.net", "rsnn_test.npz", "compile RSNN QAT Loihi"),
        ("check RSNN Jetson", "rsnn_th1.pt", "rsnn_th1_jetson", "rsnn_test.npz", "compile RSNN Jetson"),
        ("check LSTM Jetson", "lstm.pt", "lstm_jetson", "lstm_test.npz", "compile LSTM Jetson"),
    ):
        p.api(name, "check", out / model, artefact=out / artefact, data=out / test, needs=(needs, f"test split {test}"))

    (out / FIGURES).mkdir(exist_ok=True)
    p.api("map RSNN Loihi", "map", out / "rsnn_th1.net", plot=out / FIGURES / "core_map.png",
          needs=("compile RSNN Loihi",))
    p.api("energy RSNN Loihi", "report", out / "rsnn_th1.net", energy=True, data=out / "rsnn_test.npz",
          limit=ENERGY_SAMPLES, needs=("compile RSNN Loihi", "test split rsnn_test.npz"))
    # one model on every target, on the same test samples and time base (snncc compare): the cross-platform table
    p.api("compare RSNN", "compare", out / "rsnn_th1.pt", targets="loihi,xylo,jetson,c", data=out / "rsnn_test.npz",
          scale="global", allow_reset_change=True, output=out / "compare_rsnn.md",
          figure=out / FIGURES / "compare_rsnn.png", needs=("train RSNN th1", "test split rsnn_test.npz"))
    p.api("compare LSTM", "compare", out / "lstm.pt", targets="jetson,loihi,xylo,c", data=out / "lstm_test.npz",
          output=out / "compare_lstm.md", needs=("train LSTM", "test split lstm_test.npz"))

    if args.baselines:
        baselines(p, out, frames, events, seed)
    figures = write_figures(p, results(p))
    res = results(p) | {"figures": figures}
    from snncc.atomic import write_text_atomic

    write_text_atomic(out / "results.json", json.dumps(res, indent=2) + "\n")
    write_text_atomic(out / "results.md", markdown(res))
    print()
    print(markdown(res))
    print(f"wrote {out / 'results.md'} and {out / 'results.json'}"
          + (f"; figures in {out / FIGURES}: {', '.join(Path(f).name for f, _ in figures.values())}" if figures else ""))
    return 1 if any(st.status == "failed" for st in p.steps) else 0


if __name__ == "__main__":
    sys.exit(main())
