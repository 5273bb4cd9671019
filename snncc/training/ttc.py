"""Time to classification (TTC): the share of the signal a model needs before it is right for good.

For the prefix of k of the T steps (signal fraction f_k = k / T; the paper's whole Braille
signal is 1.35 s) a model predicts p_k:

* spiking models (rsnn, ffsnn): argmax of the output spike counts of steps 1..k (one run;
  a causal network's first k outputs do not depend on later inputs), ties to the lowest index;
* LSTM / eLSTM: the dense readout of the running hidden state after step k (one run);
* buffered classifiers (fcn, resnet, encoder, tcnn, inception): the model applied to the first
  k frames followed by T - k frames of zeros (the zero-padded truncated input: they take exactly
  T frames), one run per k.

TTC of a sample = f_k* for the smallest k* with p_j = label for every j >= k*; undefined (None)
when the prediction on the whole signal is wrong. Averages (mean, median) are over the samples
with a TTC; ``accuracy[k]`` is the share of samples with p_k = label.
"""

from __future__ import annotations

import io
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import torch

from snncc.atomic import write_bytes_atomic
from snncc.models import LSTMClassifier, SpikingClassifier
from snncc.models.baselines import BufferedClassifier

METHODS = {
    "spiking": "cumulative output spike counts of steps 1..k",
    "lstm": "readout of the running hidden state after step k",
    "buffered": "first k frames, then zeros up to the model's T (zero-padded truncated input)",
}


@dataclass
class TTCRecord:
    model: str                      # label (file name)
    kind: str
    method: str
    steps: int
    dt_s: float | None
    samples: int
    data: str
    fractions: list = field(default_factory=list)       # k / T, k = 1..T
    accuracy: list = field(default_factory=list)        # share correct at each fraction
    per_sample: list = field(default_factory=list)      # TTC fraction or None (wrong on the whole signal)
    mean_ttc: float | None = None
    median_ttc: float | None = None
    final_accuracy: float = 0.0
    never_correct_share: float = 0.0
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)

    def row(self) -> str:
        mean = "—" if self.mean_ttc is None else f"{self.mean_ttc:.3f}"
        median = "—" if self.median_ttc is None else f"{self.median_ttc:.3f}"
        seconds = "" if self.mean_ttc is None or self.dt_s is None else f" ({self.mean_ttc * self.steps * self.dt_s:.3f} s)"
        return (f"| {self.model} | {self.kind} | {100 * self.final_accuracy:.1f} % | {mean}{seconds} | {median} | "
                f"{100 * self.never_correct_share:.1f} % | {self.samples} |")


TABLE_HEADER = ("| model | kind | accuracy (whole signal) | mean TTC (fraction) | median TTC | "
                "no TTC (wrong at the end) | samples |\n|---|---|---|---|---|---|---|")


def method_of(model: torch.nn.Module) -> str:
    if isinstance(model, SpikingClassifier):
        return "spiking"
    if isinstance(model, LSTMClassifier):
        return "lstm"
    if isinstance(model, BufferedClassifier):
        return "buffered"
    raise TypeError(f"no TTC rule for {type(model).__name__}")


@torch.no_grad()
def prefix_predictions(model: torch.nn.Module, inputs: torch.Tensor, batch_size: int = 64) -> np.ndarray:
    """(N, T) predictions p_k of ``model`` on the first k steps of each (N, T, C) input, k = 1..T."""
    model.eval()
    method = method_of(model)
    out = []
    for start in range(0, inputs.shape[0], batch_size):
        x = inputs[start:start + batch_size].to(torch.float32)
        if method == "spiking":
            spikes, _ = model(x)
            out.append(torch.argmax(torch.cumsum(spikes, dim=1), dim=2))
        elif method == "lstm":
            hidden, _ = model.lstm(x)
            out.append(torch.argmax(model.fc(hidden), dim=2))
        else:
            steps = x.shape[1]
            cols = []
            for k in range(1, steps + 1):
                xk = x.clone()
                xk[:, k:] = 0.0
                cols.append(torch.argmax(model(xk), dim=1))
            out.append(torch.stack(cols, dim=1))
    return torch.cat(out).cpu().numpy()


def ttc_of(predictions: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Per sample TTC as a fraction (NaN when wrong at the end) from (N, T) prefix predictions."""
    correct = predictions == np.asarray(labels)[:, None]
    steps = correct.shape[1]
    # stays correct from k on: reverse cumulative AND
    stays = np.flip(np.logical_and.accumulate(np.flip(correct, axis=1), axis=1), axis=1)
    first = np.argmax(stays, axis=1)                   # first k (0-based) from which it stays correct
    ttc = (first + 1) / steps
    return np.where(stays[:, -1], ttc, np.nan)


def time_to_classification(model: torch.nn.Module, inputs: torch.Tensor, labels, *, label: str = "model",
                           kind: str | None = None, dt_s: float | None = None, data: str = "") -> TTCRecord:
    """The TTC record of ``model`` on (N, T, C) ``inputs`` with integer ``labels``."""
    labels = np.asarray(labels)
    method = method_of(model)
    preds = prefix_predictions(model, inputs)
    ttc = ttc_of(preds, labels)
    steps = preds.shape[1]
    valid = ttc[~np.isnan(ttc)]
    correct = preds == labels[:, None]
    return TTCRecord(
        model=label, kind=kind or method, method=METHODS[method], steps=steps, dt_s=dt_s, samples=int(labels.size),
        data=data, fractions=[(k + 1) / steps for k in range(steps)],
        accuracy=[float(a) for a in correct.mean(axis=0)],
        per_sample=[None if math.isnan(v) else float(v) for v in ttc],
        mean_ttc=float(valid.mean()) if valid.size else None,
        median_ttc=float(np.median(valid)) if valid.size else None,
        final_accuracy=float(correct[:, -1].mean()), never_correct_share=float(np.isnan(ttc).mean()),
    )


def ttc_table(records: list[TTCRecord]) -> str:
    return "\n".join([TABLE_HEADER] + [r.row() for r in records]) + "\n"


def plot_accuracy_vs_fraction(records: list[TTCRecord], path: str | Path, title: str | None = None) -> None:
    """Accuracy vs signal fraction of several models in one figure, written atomically (format from suffix)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 4.2))
    ax = fig.add_subplot()
    for r in records:
        ax.plot(r.fractions, [100 * a for a in r.accuracy], label=f"{r.model} ({r.kind})")
    ax.set_xlabel("share of the signal seen (k / T)")
    ax.set_ylabel("test accuracy (%)")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title, fontsize=9)
    buf = io.BytesIO()
    suffix = Path(path).suffix.lstrip(".").lower() or "png"
    fig.savefig(buf, format=suffix, dpi=120, bbox_inches="tight")
    write_bytes_atomic(path, buf.getvalue())


FIGURE_FORMATS = ("png", "pdf", "svg")
RULE = ("TTC = the smallest k/T after which the prediction is correct at every later prefix; "
        "None when wrong on the whole signal; means over the samples with a TTC")


def check_figure_path(path: str | Path) -> None:
    """A figure's format is its suffix, one of ``FIGURE_FORMATS``."""
    from snncc.errors import SnnccError

    if Path(path).suffix.lstrip(".").lower() not in FIGURE_FORMATS:
        raise SnnccError(f"the figure must be one of {', '.join(FIGURE_FORMATS)}", file=str(path), field="--figure")


def ttc_payload(records: list[TTCRecord]) -> dict:
    """The records of several models under the rule they follow (what ``--output`` and ``--json`` hold)."""
    return {"rule": RULE, "models": [r.as_dict() for r in records]}


def plot_records(records: list[TTCRecord], path: str | Path) -> None:
    """Accuracy vs signal fraction of ``records`` in one figure, titled, marked SYNTHETIC when any data are."""
    synthetic = any("SYNTHETIC" in r.data for r in records)
    plot_accuracy_vs_fraction(records, path, title="accuracy vs share of the signal seen"
                              + (" (SYNTHETIC data)" if synthetic else ""))


def ttc_of_checkpoints(models: list[str | Path], data: list[str | Path], split: str = "test") -> list[TTCRecord]:
    """TTC records of snncc checkpoints; each takes the first ``data`` set of its encoding (events or
    frames). ``split``: "test" (the checkpoint's own test samples, when its split describes the set)
    or "all"."""
    from snncc.errors import SnnccError
    from snncc.frontends.checkpoint import is_checkpoint, module_from_checkpoint
    from snncc.frontends.torchfile import load_torch_file
    from snncc.training.training_set import load_training_data
    from snncc.training.pipeline import assigned

    if split not in ("test", "all"):
        raise SnnccError("must be test or all", field="--split")
    if not data:
        raise SnnccError("give at least one data set", field="--data")
    records = []
    for path in models:
        obj = load_torch_file(path)
        if not is_checkpoint(obj):
            raise SnnccError("not an snncc checkpoint (train one with snncc train)", file=str(path), field="format")
        module = module_from_checkpoint(obj, source=str(path))
        kind = obj["architecture"]["kind"]
        meta = obj.get("metadata") if isinstance(obj.get("metadata"), dict) else {}
        threshold = int(meta.get("threshold") or 1)
        time_bin = float(meta.get("time_bin_size_ms") or 5)
        chosen, reasons = None, []
        for d in data:
            try:
                chosen = load_training_data(d, kind, threshold, time_bin)
                break
            except SnnccError as err:
                reasons.append(err.line())
        if chosen is None:
            raise SnnccError(f"no --data set fits this {kind} ({'; '.join(reasons)})", file=str(path), field="--data")
        x, y, notes = chosen.inputs, chosen.labels.numpy(), []
        assignment = meta.get("split_assignment")
        if split == "test" and isinstance(assignment, str) and len(assignment) == y.size:
            idx = assigned(assignment, "test")
            x, y = x[idx], y[idx]
            notes.append("the checkpoint's own test split")
        else:
            notes.append("all samples of the set" + ("" if split == "all" else
                                                     " (the checkpoint's split does not describe this set)"))
        if isinstance(module, BufferedClassifier) and x.shape[1] != module.config.n_steps:
            raise SnnccError(f"the {kind} takes {module.config.n_steps} frames, the set has {x.shape[1]}",
                             file=str(chosen.source), field="inputs")
        record = time_to_classification(module, x, y, label=Path(path).name, kind=kind, dt_s=meta.get("dt"),
                                        data=f"{chosen.source} ({'SYNTHETIC' if chosen.facts()['synthetic'] else 'recorded'})")
        record.notes = notes
        records.append(record)
    return records
