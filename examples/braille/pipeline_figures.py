"""The Braille pipeline's figures (matplotlib, Agg backend), drawn from its results (``results.json``).

    training_curves.png   loss and accuracy per epoch of every model trained, chance marked
    accuracy.png          accuracy per model: float, quantized, Loihi emulated, Jetson (ONNX Runtime),
                          beside the paper's figures on the real recordings
    energy_delay.png      Loihi energy and delay per sample and cores: snncc's ESTIMATE beside the
                          paper's measurement
    (core_map.png is drawn by ``snncc.api.map(..., plot=...)`` as a step of the pipeline)

Every figure says SYNTHETIC (the data) and ESTIMATE (energy, delay) where they apply. Each
``*_figure`` function builds the matplotlib figure (None when the results hold nothing to draw);
the function of the same name without ``_figure`` writes it as a PNG and returns its path.
"""

from __future__ import annotations

from pathlib import Path

SYNTHETIC = "SYNTHETIC Braille data (not the paper's recordings)"
COLUMNS = (("float", "float (PyTorch)", "tab:blue"), ("quantized", "quantized (Loihi weights, float)", "tab:cyan"),
           ("loihi_emulated", "Loihi, bit-exact emulator", "tab:orange"),
           ("jetson", "Jetson artefact (ONNX Runtime)", "tab:green"))
PAPER_COLUMNS = (("paper_float", "paper: PyTorch (real data)"), ("paper_loihi", "paper: on Loihi (real data)"))


def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    from snncc.atomic import atomic_path

    plt = _pyplot()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fig.savefig(fh, format="png", dpi=110, bbox_inches="tight", metadata={"Software": None})
    plt.close(fig)
    return path


def _written(fig, path: Path) -> Path | None:
    return None if fig is None else _save(fig, path)


def training_curves(curves: list[dict], chance_percent: float, path: Path) -> Path | None:
    return _written(training_curves_figure(curves, chance_percent), path)


def accuracy(models: list[dict], path: Path) -> Path | None:
    return _written(accuracy_figure(models), path)


def energy_delay(estimate: dict | None, path: Path) -> Path | None:
    return _written(energy_delay_figure(estimate), path)


def training_curves_figure(curves: list[dict], chance_percent: float):
    """``curves``: {"model", "epochs": [{"epoch", "loss", "train_accuracy", "test_accuracy"}]} per model trained.
    Loss on a log axis: each model has its own loss (the SNNs' includes spike regularisation)."""
    from snncc.log_axis import readable_log_axis

    curves = [{**c, "epochs": [e for e in c.get("epochs") or [] if None not in e.values()]} for c in curves]
    curves = [c for c in curves if c["epochs"]]
    if not curves:
        return None
    plt = _pyplot()
    fig, (loss_ax, acc_ax) = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    for i, curve in enumerate(curves):
        color = f"C{i % 10}"
        epochs = [e["epoch"] for e in curve["epochs"]]
        loss_ax.plot(epochs, [e["loss"] for e in curve["epochs"]], marker="o", color=color, label=curve["model"])
        acc_ax.plot(epochs, [100 * e["test_accuracy"] for e in curve["epochs"]], marker="o", color=color,
                    label=f"{curve['model']}: test")
        acc_ax.plot(epochs, [100 * e["train_accuracy"] for e in curve["epochs"]], ls="--", color=color, alpha=0.6,
                    label=f"{curve['model']}: train (running)")
    acc_ax.axhline(chance_percent, color="0.5", ls=":", label=f"chance ({chance_percent:.1f} %)")
    top = max(100 * max(e["test_accuracy"], e["train_accuracy"]) for c in curves for e in c["epochs"])
    loss_ax.set(xlabel="epoch", ylabel="training loss (each model's own)", title="loss per epoch")
    acc_ax.set(xlabel="epoch", ylabel="accuracy %", title="accuracy per epoch", ylim=(0, min(100.0, 1.15 * top + 5)))
    for ax in (loss_ax, acc_ax):
        ax.grid(alpha=0.3)
        ax.xaxis.get_major_locator().set_params(integer=True)
    if all(e["loss"] > 0 for c in curves for e in c["epochs"]):
        readable_log_axis(loss_ax, "y")
    handles, labels = acc_ax.get_legend_handles_labels()      # one legend, below the axes: it covers no point
    fig.legend(handles, labels, loc="outside lower center", ncol=min(4, len(labels)), fontsize=7)
    fig.suptitle(f"Training curves -- {SYNTHETIC}", fontsize=10)
    return fig


def accuracy_figure(models: list[dict]):
    """``models``: {"model", "float", "quantized", "loihi_emulated", "jetson", "paper_float", "paper_loihi"}
    (percent or None) per model; a bar per value this run has, the paper's figures as markers."""
    models = [m for m in models if any(m.get(k) is not None for k, _, _ in COLUMNS)]
    if not models:
        return None
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(max(7.0, 2.3 * len(models)), 4.6))
    width = 0.8 / len(COLUMNS)
    for j, (key, label, color) in enumerate(COLUMNS):
        xs = [i - 0.4 + (j + 0.5) * width for i, m in enumerate(models) if m.get(key) is not None]
        ys = [m[key] for m in models if m.get(key) is not None]
        if xs:
            bars = ax.bar(xs, ys, width=width, color=color, label=label)
            ax.bar_label(bars, labels=[f"{y:.1f}" for y in ys], fontsize=6, padding=1)
    beside = {"paper_float": "float", "paper_loihi": "loihi_emulated"}     # each paper figure over its own bar
    slot = {key: j for j, (key, _, _) in enumerate(COLUMNS)}
    for (key, label), marker in zip(PAPER_COLUMNS, ("D", "*")):
        xs = [i for i, m in enumerate(models) if m.get(key) is not None]
        if xs:
            offset = -0.4 + (slot[beside[key]] + 0.5) * width
            ax.scatter([i + offset for i in xs], [models[i][key] for i in xs], marker=marker, s=90, color="k",
                       edgecolors="w", linewidths=0.5, zorder=3, label=label)
    ax.set_xticks(range(len(models)), [m["model"] for m in models], fontsize=8)
    ax.set(ylabel="test accuracy %", ylim=(0, 105))
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title(f"Accuracy per model and deployment -- this run on {SYNTHETIC}; paper on the real recordings",
                 fontsize=9)
    return fig


def energy_delay_figure(estimate: dict | None):
    """``estimate``: {"energy_uj_per_sample", "delay_ms_per_sample", "cores", "paper_measurement": {the same
    keys}} (``results.json``'s ``loihi.estimate``, from ``snncc report --energy``)."""
    if not estimate:
        return None
    paper = estimate["paper_measurement"]
    figures = (("energy per sample (uJ)", estimate["energy_uj_per_sample"], paper["energy_uj_per_sample"]),
               ("delay per sample (ms)", estimate["delay_ms_per_sample"], paper["delay_ms_per_sample"]),
               ("cores", estimate["cores"], paper["cores"]))
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.8), layout="constrained")
    for ax, (label, ours, theirs) in zip(axes, figures):
        bars = ax.bar([0, 1], [ours, theirs], color=["tab:orange", "0.35"])
        bars[0].set_hatch("//")                     # the estimate is drawn hatched
        ax.bar_label(bars, labels=[f"{ours:.3g}", f"{theirs:.3g}"], fontsize=8)
        ax.set_xticks([0, 1], ["snncc\nESTIMATE", "paper\nMEASURED"], fontsize=8)
        ax.set_title(label, fontsize=9)
        ax.margins(y=0.15)
    fig.suptitle("Loihi 1 per sample: snncc's ESTIMATE (Davies 2018 Table 2, dynamic energy only; this bundle on "
                 "SYNTHETIC inputs), not a measurement,\nbeside the paper's MEASUREMENT (its RSNN th1 on the chip, "
                 "real data)", fontsize=9)
    return fig
