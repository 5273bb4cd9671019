"""``snncc train`` as a Python function: data -> split -> model -> training -> checkpoint record.

Also quantization-aware fine-tuning from a trained checkpoint, on the same split it was trained on.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Callable

import numpy as np
import torch

from snncc.targets import DEFAULT_TARGET
from snncc.errors import SnnccError, one_line
from snncc.frontends.checkpoint import is_checkpoint, module_from_checkpoint, save_checkpoint
from snncc.frontends.params import PaperParams, load_params
from snncc.frontends.torchfile import load_torch_file
from snncc.models import SNNConfig, SpikingClassifier, count_trainable
from snncc.models.baselines import BASELINE_KINDS
from snncc.models.size import check_snn_size
from snncc.training.baseline_presets import FAMILY
from snncc.training.device import resolve_device
from snncc.training.training_set import EVENT_KINDS, FRAME_DT_S, TrainingData, load_training_data, subset_indices
from snncc.training.presets import OptimiserSettings, paper_preset, with_overrides
from snncc.training.qat import chip_parameters, quantized_forward, target_arithmetic
from snncc.data.split import Split, stratified_split
from snncc.training.trainer import EpochRecord, History, TrainSettings, accuracy, build_model, train_model
from snncc.progress import Progress as VerbProgress

KINDS = ("rsnn", "ffsnn", "lstm", "elstm") + BASELINE_KINDS
N_SNN_OUTPUTS = 28   # 27 letters + 1 spare class (the authors' network)


@dataclass
class TrainRequest:
    kind: str
    data: str
    output: str
    threshold: int = 1
    epochs: int = 300
    subset: int | None = None
    seed: int = 0
    order: str = "spytorch"
    val_fraction: float = 0.0
    batch_size: int | None = None     # None: 128 (the paper's) or the baseline family's own
    lr: float | None = None           # None: the paper's (Adamax 0.0015) or the baseline family's own
    overrides: dict = field(default_factory=dict)
    params_file: str | None = None
    qat_from: str | None = None
    qat_epochs: int = 3
    qat_target: str = DEFAULT_TARGET         # the target whose arithmetic QAT trains through (capability ``arithmetic``)
    device: str = "auto"
    n_hidden: int | None = None      # spiking models: hidden neurons (None: the paper's 450)


@dataclass
class TrainResult:
    kind: str
    output: str
    parameters: int
    hyper_parameters: dict
    optimiser: dict
    data: dict
    split: dict
    history: dict
    epochs: list
    quantization: dict | None = None
    notes: list = field(default_factory=list)
    device: str = "cpu"        # where the epochs ran (the checkpoint itself is always saved on the CPU)

    def as_dict(self) -> dict:
        """What ``snncc train --json`` prints."""
        from snncc.records import to_jsonable

        return to_jsonable(self)

    def render_text(self, console) -> None:
        """Parameters, data, split, the selected epoch's accuracies, QAT's losses, the file written."""
        h, d, s = self.history, self.data, self.split
        console.print(f"[bold]{self.kind}[/bold]: {self.parameters:,} trainable parameters; "
                      f"{d['samples']} samples of {d['encoding']} ({d['steps']} steps x "
                      f"{d['channels']} channels){' -- SYNTHETIC data' if d['synthetic'] else ''}")
        console.print(f"split (seed {s['seed']}): train {s['train']}, val {s['val']}, test {s['test']}")
        console.print(f"epochs run: {h['epochs_run']} on {self.device} ({h['seconds']:.1f} s); best epoch "
                      f"{h['best_epoch']}: test accuracy {100 * h['test_accuracy']:.2f} %"
                      + (f", validation {100 * h['val_accuracy']:.2f} %" if h['val_accuracy'] is not None else ""))
        for note in [h["note"]] + [n for n in self.notes if n != h["note"] and "SYNTHETIC" not in n]:
            console.print(f"note: {note}")
        if self.quantization:
            q = self.quantization
            console.print(f"quantization-aware fine-tuning ({q['epochs']} epochs): float "
                          f"{100 * q['before']['float_test_accuracy']:.2f} % -> {q.get('target', 'Loihi')}-quantized "
                          f"{100 * q['before']['quantized_test_accuracy']:.2f} % before (loss "
                          f"{q['loss_before_points']:.2f} points), {100 * q['after']['quantized_test_accuracy']:.2f} % "
                          f"after (loss {q['loss_after_points']:.2f} points vs the original float model)")
            console.print(f"note: {q['note']}")
        console.print(f"wrote {one_line(self.output)}", markup=False)


def hyper_parameters(req: TrainRequest) -> PaperParams:
    base = load_params(req.params_file) if req.params_file else paper_preset(req.threshold)
    return with_overrides(base, req.overrides) if req.overrides else base


SPLIT_CODES = {"train": "r", "test": "t", "val": "v"}   # "-": not used (outside --subset)


def split_assignment(split: Split, n: int) -> str:
    """One character per sample of the data set: r(train) t(est) v(al) or - (unused)."""
    codes = np.full(n, "-")
    for part, code in SPLIT_CODES.items():
        codes[getattr(split, part)] = code
    return "".join(codes.tolist())


def assigned(assignment: str, part: str) -> np.ndarray:
    """Sample indices of ``part`` ("train", "test", "val") in a checkpoint's ``split_assignment``."""
    codes = np.frombuffer(assignment.encode("ascii"), dtype="S1").astype(str)
    return np.flatnonzero(codes == SPLIT_CODES[part])


def _prepare(req: TrainRequest, data: TrainingData, stored: str | None = None):
    """The split (sample indices into the data set) and the (inputs, labels) of each part.

    ``stored``: a checkpoint's ``split_assignment``, reused verbatim (fine-tuning never trains on
    the samples the model was tested on).
    """
    if stored is not None:
        n = int(data.labels.shape[0])
        if not isinstance(stored, str) or len(stored) != n or set(stored) - set(SPLIT_CODES.values()) - {"-"}:
            raise SnnccError(f"the checkpoint's split does not describe this set of {n} samples", file=req.data, field="--data")
        parts = {k: assigned(stored, k) for k in SPLIT_CODES}
        split = Split(parts["train"], parts["test"], parts["val"], req.seed, 0.2, req.val_fraction)
    else:
        chosen = subset_indices(data.labels.numpy(), req.subset, req.seed)
        local = stratified_split(data.labels.numpy()[chosen], seed=req.seed, val_fraction=req.val_fraction)
        split = Split(chosen[local.train], chosen[local.test], chosen[local.val], req.seed,
                      local.test_fraction, local.val_fraction)
    pick = lambda idx: (data.inputs[idx], data.labels[idx])  # noqa: E731
    return split, pick(split.train), pick(split.test), (pick(split.val) if split.val.size else None)


def _new_model(req: TrainRequest, hp: PaperParams, data: TrainingData) -> torch.nn.Module:
    torch.manual_seed(req.seed)
    channels = int(data.inputs.shape[-1])
    n_classes = int(data.labels.max()) + 1
    if req.kind in ("rsnn", "ffsnn"):
        if n_classes > N_SNN_OUTPUTS:
            raise SnnccError(f"labels reach {n_classes - 1}; the SNN has {N_SNN_OUTPUTS} outputs", file=data.source,
                             field="labels")
        size = {} if req.n_hidden is None else {"n_hidden": int(req.n_hidden)}
        check_snn_size(channels, hp.nb_input_copies, size.get("n_hidden", SNNConfig.n_hidden), N_SNN_OUTPUTS,
                       req.kind == "rsnn", min(batch_size_of(req), int(data.labels.shape[0])), int(data.inputs.shape[1]))
        model = build_model(req.kind, n_inputs=channels, n_outputs=N_SNN_OUTPUTS, input_copies=hp.nb_input_copies,
                            tau_mem=hp.tau_mem, tau_syn=hp.tau_syn, dt=hp.dt, scale=hp.scale, order=req.order, **size)
        model.reset_parameters(hp.fwd_weight_scale, hp.weight_scale_factor)
        return model
    if req.kind in BASELINE_KINDS:
        return build_model(req.kind, n_inputs=channels, n_steps=int(data.inputs.shape[1]),
                           n_outputs=max(n_classes, 27), dt=FRAME_DT_S)
    dt = hp.dt if req.kind == "elstm" else FRAME_DT_S
    model = build_model(req.kind, n_inputs=channels, n_outputs=max(n_classes, 27), dt=dt)
    if req.kind == "elstm":
        model.init_for_events(int(data.inputs.shape[1]))   # see snncc.models.lstm: why the default does not learn
    return model


def batch_size_of(req: TrainRequest) -> int:
    if req.batch_size is not None:
        return req.batch_size
    return FAMILY[req.kind].batch_size if req.kind in BASELINE_KINDS else OptimiserSettings().batch_size


def optimiser_record(req: TrainRequest, epochs: int) -> dict:
    """The optimiser and schedule used: the paper's (Adamax) or, for the baselines, their family's."""
    if req.kind in BASELINE_KINDS:
        fam = FAMILY[req.kind]
        return {**fam.as_dict(), "lr": req.lr if req.lr is not None else fam.lr, "batch_size": batch_size_of(req),
                "epochs": epochs}
    opt = OptimiserSettings(epochs=epochs, batch_size=batch_size_of(req))
    return {**opt.as_dict(), "lr": req.lr if req.lr is not None else opt.lr, "optimiser": "adamax"}


def _settings(req: TrainRequest, hp: PaperParams, epochs: int) -> TrainSettings:
    rec = optimiser_record(req, epochs)
    spiking = req.kind in ("rsnn", "ffsnn")
    extra = {}
    if req.kind in BASELINE_KINDS:
        extra = {"optimiser": rec["optimiser"], "loss": rec["loss"], "plateau": rec["plateau"]}
    return TrainSettings(epochs=epochs, batch_size=rec["batch_size"], lr=rec["lr"], betas=tuple(rec["betas"]),
                         seed=req.seed, reg_spikes=hp.reg_spikes if spiking else 0.0,
                         reg_neurons=hp.reg_neurons if spiking else 0.0, **extra)


def _metadata(req, hp, data, split, history: History, extra=None) -> dict:
    facts = data.facts()
    meta = {
        "model_kind": req.kind,
        "trained_by": "snncc train",
        "data": facts,
        "synthetic_data": facts["synthetic"],
        "threshold": req.threshold,
        "time_bin_size_ms": hp.time_bin_size if req.kind in EVENT_KINDS else FRAME_DT_S * 1000,
        "dt": hp.dt if req.kind in EVENT_KINDS else FRAME_DT_S,
        "encoding": facts["encoding"],
        "preset": hp.as_dict(),
        "update_order": req.order if req.kind in ("rsnn", "ffsnn") else None,
        "optimiser": optimiser_record(req, len(history.epochs)),
        "split_seed": req.seed,
        "subset": req.subset,
        "split": split.summary(),
        "split_assignment": split_assignment(split, int(data.labels.shape[0])),
        "best_epoch": history.best_epoch,
        "epoch_selected_on": history.selected_on,
        "selection_note": history.note,
        "test_accuracy": history.best_test_accuracy,
        "val_accuracy": history.best_val_accuracy,
    }
    if facts.get("classes"):
        meta["classes"] = list(facts["classes"]) + (["spare"] if req.kind in ("rsnn", "ffsnn") and len(facts["classes"]) == 27 else [])
    meta.update(extra or {})
    return meta


def train(req: TrainRequest, progress: VerbProgress | None = None, data: TrainingData | None = None,
          on_epoch: Callable[[EpochRecord], None] | None = None) -> TrainResult:
    """Train a model from scratch and write its checkpoint (``data``: already loaded, else from req.data).

    ``progress(done, total, "epoch e/E")``: after each batch; ``on_epoch(record)``: after each epoch
    with its ``EpochRecord`` (see ``train_model``).
    """
    if req.kind not in KINDS:
        raise SnnccError(f"unknown model {req.kind!r} (known: {', '.join(KINDS)})", field="model")
    if req.epochs < 1:
        raise SnnccError("must be >= 1", field="--epochs")
    if req.batch_size is not None and req.batch_size < 1:
        raise SnnccError("must be >= 1", field="--batch-size")
    if req.lr is not None and not (0 < req.lr < 10):
        raise SnnccError("must be > 0 and < 10", field="--lr")
    device = resolve_device(req.device)
    hp = hyper_parameters(req)
    if data is None:
        data = load_training_data(req.data, req.kind, req.threshold, hp.time_bin_size)
    split, train_set, test_set, val_set = _prepare(req, data)
    model = _new_model(req, hp, data)
    settings = _settings(req, hp, req.epochs)
    history = train_model(model, train_set, test_set, settings, val=val_set, progress=progress, device=device,
                          on_epoch=on_epoch)
    meta = _metadata(req, hp, data, split, history, {"trained_on": str(device)})
    save_checkpoint(model, req.output, meta)
    return TrainResult(req.kind, req.output, count_trainable(model), hp.as_dict(), asdict(settings), data.facts(),
                       split.summary(), history.summary(), [asdict(e) for e in history.epochs],
                       notes=[history.note] + [n for n in (history.collapse_note(),) if n]
                       + ([] if not data.facts()["synthetic"] else ["trained on SYNTHETIC data"]),
                       device=str(device))


def _check_fits(model: SpikingClassifier, data: TrainingData, checkpoint: str) -> None:
    """The data must fit the checkpoint's model: its input channels, and labels below its outputs."""
    cfg = model.config
    channels = int(data.inputs.shape[-1])
    if channels != cfg.n_inputs:
        raise SnnccError(f"has {channels} input channels; the model in {checkpoint} takes {cfg.n_inputs}",
                         file=data.source, field="inputs")
    top = int(data.labels.max()) if data.labels.numel() else -1
    if top >= cfg.n_outputs:
        raise SnnccError(f"labels reach {top}; the model in {checkpoint} has {cfg.n_outputs} outputs (classes "
                         f"0..{cfg.n_outputs - 1})", file=data.source, field="labels")


def finetune(req: TrainRequest, progress: VerbProgress | None = None, data: TrainingData | None = None,
             on_epoch: Callable[[EpochRecord], None] | None = None) -> TrainResult:
    """Quantization-aware fine-tuning of a trained spiking checkpoint, on its own split
    (``progress``, ``on_epoch``: as for ``train``)."""
    device = resolve_device(req.device)
    obj = load_torch_file(req.qat_from)
    if not is_checkpoint(obj):
        raise SnnccError("not an snncc checkpoint (train one with snncc train)", file=req.qat_from, field="format")
    model = module_from_checkpoint(obj, source=req.qat_from)
    if not isinstance(model, SpikingClassifier):
        raise SnnccError("quantization-aware fine-tuning applies to rsnn/ffsnn checkpoints only",
                         file=req.qat_from, field="architecture.kind")
    if model.config.kind != req.kind:
        raise SnnccError(f"checkpoint holds a {model.config.kind}, not a {req.kind}", file=req.qat_from, field="architecture.kind")
    if req.qat_epochs < 1:
        raise SnnccError("must be >= 1", field="--qat-epochs")
    src = obj.get("metadata", {})
    preset = src.get("preset")
    hp = with_overrides(paper_preset(1), preset) if preset else hyper_parameters(req)
    # the checkpoint's own split: same seed, subset and validation share
    req.seed = int(src.get("split_seed", req.seed))
    req.subset = src.get("subset", req.subset)
    req.threshold = int(src.get("threshold", req.threshold))
    req.order = model.config.order
    req.val_fraction = float(src.get("split", {}).get("val_fraction", req.val_fraction))
    if data is None:
        data = load_training_data(req.data, req.kind, req.threshold, hp.time_bin_size)
    _check_fits(model, data, req.qat_from)
    split, train_set, test_set, val_set = _prepare(req, data, src.get("split_assignment"))
    arithmetic = target_arithmetic(req.qat_target)

    def forward(m, x):
        return quantized_forward(m, x, arithmetic)

    before = {"float_test_accuracy": accuracy(model, *test_set),
              "quantized_test_accuracy": accuracy(model, *test_set, forward=forward),
              "quantization": dict(chip_parameters(model, arithmetic).record)}
    settings = _settings(req, hp, req.qat_epochs)
    torch.manual_seed(req.seed)
    history = train_model(model, train_set, test_set, settings, val=val_set, forward=forward, progress=progress,
                          keep_start=True, device=device, on_epoch=on_epoch)
    after = {"float_test_accuracy": accuracy(model, *test_set),
             "quantized_test_accuracy": accuracy(model, *test_set, forward=forward),
             "quantization": dict(chip_parameters(model, arithmetic).record)}
    record = {"from": str(req.qat_from), "epochs": req.qat_epochs, "target": arithmetic.label, "before": before,
              "after": after,
              "loss_before_points": 100 * (before["float_test_accuracy"] - before["quantized_test_accuracy"]),
              "loss_after_points": 100 * (before["float_test_accuracy"] - after["quantized_test_accuracy"]),
              "note": f"accuracies of the fake-quantized model ({arithmetic.label} weights, threshold and decays in float; the "
                      "chip's per-step integer truncation of current and voltage is not modelled -- use snncc check "
                      "for the bit-exact emulator); best epoch 0 = no fine-tuned epoch beat the starting weights, "
                      "which were kept"}
    meta = _metadata(req, hp, data, split, history, {"qat": record, "trained_by": "snncc train --qat-from",
                                                     "trained_on": str(device)})
    save_checkpoint(model, req.output, meta)
    return TrainResult(req.kind, req.output, count_trainable(model), hp.as_dict(), asdict(settings), data.facts(),
                       split.summary(), history.summary(), [asdict(e) for e in history.epochs], quantization=record,
                       notes=[history.note, "epochs selected on the fake-quantized accuracy"], device=str(device))
