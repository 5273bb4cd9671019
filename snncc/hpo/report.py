"""``snncc hpo report STUDY``: every trial, the best per objective, the hardware-aware Pareto front.

The front: COMPLETE trials not dominated on (accuracy: higher, ESTIMATED energy per sample:
lower, Loihi cores: lower). Rendered as a table, as JSON (same record) and as a figure
(accuracy vs energy and vs cores, the front highlighted, trials run with the paper's presets
starred, and the paper's own Loihi measurement -- real data, RSNN th 1 -- for scale).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path

from snncc.hpo.annealing import pareto_ranks
from snncc.hpo.outcome import TrialOutcome, directions
from snncc.training.presets import PRESETS

FRONT_AXES = ("accuracy", "energy", "cores")


@dataclass
class TrialRow:
    number: int
    state: str
    params: dict
    accuracy: float | None = None
    selected_on: str | None = None
    test_accuracy: float | None = None
    cores: int | None = None
    synops: float | None = None
    energy_uj: float | None = None          # ESTIMATE
    delay_ms: float | None = None           # ESTIMATE
    emulated_accuracy: float | None = None
    epochs_run: int | None = None
    last_intermediate: float | None = None  # pruned trials: the last reported accuracy
    paper_preset: int | None = None         # the threshold whose preset this trial ran
    retry_of: int | None = None
    checkpoint: str | None = None
    worker: str | None = None
    error: str | None = None
    hardware: dict | None = None            # the target's figures as recorded (HardwareFigures.as_dict())
    target: str = "loihi"

    def value(self, name: str) -> float | None:
        if self.target != "loihi":          # another target's objectives: keys of its figures
            from snncc.hpo.hardware import hardware_costs

            if name == "accuracy":
                return self.accuracy
            v = (self.hardware or {}).get(hardware_costs(self.target).objectives[name].key)
            return None if v is None else float(v)
        return {"accuracy": self.accuracy, "energy": self.energy_uj, "cores": self.cores, "synops": self.synops,
                "delay": self.delay_ms, "emulated_accuracy": self.emulated_accuracy}[name]


@dataclass
class HpoReport:
    study: str
    storage: str
    plan: dict
    counts: dict
    rows: list[TrialRow]
    best: dict                   # objective -> trial number
    front: list[int]             # trial numbers on the (accuracy, energy, cores) front
    paper_presets: dict
    synthetic_data: bool
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)

    def row(self, number: int) -> TrialRow:
        return next(r for r in self.rows if r.number == number)

    def render_text(self, console) -> None:
        from rich.table import Table

        p = self.plan
        console.print(f"[bold]study {self.study}[/bold] ({p.get('step')}; objectives {', '.join(p.get('objectives', []))}; "
                      f"storage {self.storage})" + ("  -- SYNTHETIC data" if self.synthetic_data else ""))
        console.print("trials: " + ", ".join(f"{k} {v}" for k, v in self.counts.items()))
        for note in self.notes:
            console.print(f"note: {note}")
        best = Table(title="best trial per objective")
        for col in ("objective", "trial", "value", "accuracy %", "cores", "energy uJ/sample (EST.)"):
            best.add_column(col, justify="right")
        for name, number in self.best.items():
            r = self.row(number)
            v = r.value(name)
            shown = f"{100 * v:.2f} %" if name in ("accuracy", "emulated_accuracy") else f"{v:,.4g}"
            best.add_row(name, str(number), shown, _pct(r.accuracy), str(r.cores), _num(r.energy_uj))
        console.print(best)
        console.print(self._table("Pareto front: accuracy (max) vs ESTIMATED energy (min) vs cores (min)",
                                  [self.row(n) for n in self.front]))
        presets = Table(title="hyper-parameters: the best trial per objective beside the paper's presets")
        keys = list(next(iter(PRESETS.values())).as_dict())
        cols = [(f"best {name} (#{n})", self.row(n).params) for name, n in self.best.items()]
        cols += [(f"paper th {th}", values) for th, values in self.paper_presets.items()]
        presets.add_column("hyper-parameter")
        for title, _ in cols:
            presets.add_column(title, justify="right")
        for k in keys:
            presets.add_row(k, *[_g(params.get(k)) for _, params in cols])
        console.print(presets)

    def _table(self, title: str, rows: list[TrialRow]):
        from rich.table import Table

        t = Table(title=title)
        for col in ("trial", "accuracy %", "cores", "synops/sample", "energy uJ (EST.)", "delay ms (EST.)",
                    "emulated %", "time_bin_size", "nb_input_copies"):
            t.add_column(col, justify="right")
        for r in rows:
            t.add_row(str(r.number) + (" *" if r.paper_preset else ""), _pct(r.accuracy), str(r.cores),
                      _num(r.synops), _num(r.energy_uj), _num(r.delay_ms), _pct(r.emulated_accuracy),
                      _g(r.params.get("time_bin_size")), _g(r.params.get("nb_input_copies")))
        return t

    def figure(self):
        """Accuracy vs energy (log axis) and vs cores, the front highlighted: a matplotlib Figure (Agg)."""
        import matplotlib

        matplotlib.use("Agg", force=True)
        import matplotlib.pyplot as plt

        from snncc.hpo.hardware import hardware_costs
        from snncc.log_axis import readable_log_axis

        published = hardware_costs(self.plan.get("target") or "loihi").published     # a measurement to show beside the trials, if any

        done = [r for r in self.rows if r.accuracy is not None and r.energy_uj is not None]
        front = [r for r in done if r.number in set(self.front)]
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
        for ax, (attr, label) in zip(axes, (("energy_uj", "energy per sample, uJ (ESTIMATE)"),
                                            ("cores", "Loihi cores"))):
            ax.scatter([getattr(r, attr) for r in done], [100 * r.accuracy for r in done], s=18, c="0.6",
                       label="trials")
            fr = sorted(front, key=lambda r: getattr(r, attr))
            ax.scatter([getattr(r, attr) for r in fr], [100 * r.accuracy for r in fr], s=36, c="tab:red",
                       label="Pareto front (acc., energy, cores)")
            pre = [r for r in done if r.paper_preset]
            if pre:
                ax.scatter([getattr(r, attr) for r in pre], [100 * r.accuracy for r in pre], marker="*", s=160,
                           c="tab:blue", label="paper's preset, trained here")
            axis = "energy" if attr == "energy_uj" else "cores"
            if axis in published and "accuracy" in published:
                ax.scatter([published[axis]], [published["accuracy"]], marker="D", s=40, c="k",
                           label=str(published.get("label", "published measurement")))
            if attr == "energy_uj":
                readable_log_axis(ax, "x")
            ax.set_xlabel(label)
            ax.set_ylabel(f"accuracy % ({self.plan.get('select', 'val')} split)")
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=7, loc="lower right")
        fig.suptitle(f"snncc hpo: study {self.study}" + (" -- SYNTHETIC data" if self.synthetic_data else ""),
                     fontsize=10)
        return fig

    def plot(self, path: str | Path) -> Path:
        """``figure()`` written atomically to ``path`` (PNG)."""
        import matplotlib.pyplot as plt

        from snncc.atomic import atomic_path

        fig = self.figure()
        path = Path(path)
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                fig.savefig(fh, format="png", dpi=110, bbox_inches="tight", metadata={"Software": None})
        plt.close(fig)
        return path


def _pct(v) -> str:
    return "-" if v is None else f"{100 * v:.2f}"


def _num(v) -> str:
    return "-" if v is None else f"{v:,.4g}"


def _g(v) -> str:
    return "-" if v is None else f"{v:.3g}"


def trial_row(t) -> TrialRow:
    from optuna.trial import TrialState

    attrs = t.user_attrs
    row = TrialRow(number=t.number, state=t.state.name, params=dict(t.params),
                   paper_preset=attrs.get("paper_preset"), worker=attrs.get("worker"), error=attrs.get("error"),
                   retry_of=t.system_attrs.get("failed_trial"))
    o = attrs.get("outcome")
    if o and t.state == TrialState.COMPLETE:
        out = TrialOutcome(**o)
        hw = out.hardware or {}
        row.params = dict(out.params)
        row.accuracy, row.selected_on, row.test_accuracy = out.accuracy, out.selected_on, out.test_accuracy
        row.cores, row.synops = hw.get("cores"), hw.get("synaptic_ops_per_sample")
        row.energy_uj, row.delay_ms = hw.get("energy_uj_per_sample"), hw.get("delay_ms_per_sample")
        row.emulated_accuracy, row.epochs_run = hw.get("emulated_accuracy"), out.epochs_run
        row.checkpoint, row.worker = out.checkpoint, out.worker
        row.hardware, row.target = dict(hw), out.target
    if t.intermediate_values:
        row.last_intermediate = float(t.intermediate_values[max(t.intermediate_values)])
    elif attrs.get("epoch_metric"):
        row.last_intermediate = float(attrs["epoch_metric"][-1])
    return row


def front_of(rows: list[TrialRow]) -> list[int]:
    """Numbers of the rows not dominated on (accuracy max, energy min, cores min)."""
    ok = [r for r in rows if r.accuracy is not None and r.energy_uj is not None and r.cores is not None]
    ranks = pareto_ranks([(-r.accuracy, r.energy_uj, float(r.cores)) for r in ok])
    return sorted(r.number for r, k in zip(ok, ranks) if k == 0)


def best_of(rows: list[TrialRow], target: str | None = None) -> dict[str, int]:
    out = {}
    for name, direction in directions(target).items():
        cand = [r for r in rows if r.value(name) is not None]
        if cand:
            sign = -1.0 if direction == "maximize" else 1.0
            out[name] = min(cand, key=lambda r: (sign * r.value(name), r.number)).number
    return out


def study_report(storage, name: str, storage_label: str = "") -> HpoReport:
    """The report of study ``name`` in ``storage`` (an Optuna storage or URL)."""
    from snncc.hpo.study import PLAN_ATTR, budget, load_study, stored_plan

    study = load_study(storage, name)
    plan = stored_plan(study)
    plan_d = plan.as_dict() if plan else dict(study.user_attrs.get(PLAN_ATTR, {}))
    rows = [trial_row(t) for t in study.get_trials(deepcopy=False)]
    b = budget(study, plan.n_trials if plan else len(rows))
    synthetic = any(TrialOutcome(**t.user_attrs["outcome"]).synthetic_data for t in study.get_trials(deepcopy=False)
                    if t.user_attrs.get("outcome"))
    notes = ["energy and delay are ESTIMATES (Davies 2018 Table 2 costs, dynamic energy only), not measurements"]
    if synthetic:
        notes.append("trained on SYNTHETIC data: these accuracies are not the paper's")
    if plan_d.get("select") == "test":
        notes.append("selected on the TEST split as the paper did: accuracies are optimistic")
    retried = [r for r in rows if r.retry_of is not None]
    if retried:
        notes.append("re-queued after a kill or Ctrl-C: " + ", ".join(f"trial {r.retry_of} -> {r.number}" for r in retried))
    counts = {"complete": b.complete, "pruned": b.pruned, "failed": b.failed, "killed and re-queued": b.retried,
              "running": b.running, "waiting": b.waiting, "budget": b.n_trials,
              "cancelled over budget": b.cancelled}
    return HpoReport(study=name, storage=storage_label, plan=plan_d, counts=counts, rows=rows,
                     best=best_of(rows, plan_d.get("target")),
                     front=front_of(rows), paper_presets={th: p.as_dict() for th, p in PRESETS.items()},
                     synthetic_data=synthetic, notes=notes)
