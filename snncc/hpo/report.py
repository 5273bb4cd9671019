"""``snncc hpo report STUDY``: every trial, the best per objective, the hardware-aware Pareto front.

The columns are the study's target's: the figures its ``hardware`` capability declares (``columns``:
key, heading, unit scale), the objectives among them, and the objectives its front weighs
(``front``). The front: COMPLETE trials not dominated on accuracy (higher) and those objectives, each
in its direction (Loihi: ESTIMATED energy per sample, lower; cores, lower. Xylo: hidden neurons,
lower; real-time margin, higher; feasible, higher). Rendered as a table, as JSON (same record, each
row's figures by name) and as a figure (accuracy vs the front's first two objectives, the front
highlighted, trials run with the paper's presets starred, and the target's published measurement,
if any -- Loihi: the paper's, real data, RSNN th 1 -- for scale).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets import DEFAULT_TARGET
from snncc.hpo.annealing import pareto_ranks
from snncc.hpo.outcome import TrialOutcome, directions
from snncc.training.presets import PRESETS

if TYPE_CHECKING:
    from snncc.targets.base import Figure


@dataclass
class TrialRow:
    number: int
    state: str
    params: dict
    accuracy: float | None = None
    selected_on: str | None = None
    test_accuracy: float | None = None
    epochs_run: int | None = None
    last_intermediate: float | None = None  # pruned trials: the last reported accuracy
    paper_preset: int | None = None         # the threshold whose preset this trial ran
    retry_of: int | None = None
    checkpoint: str | None = None
    worker: str | None = None
    error: str | None = None
    hardware: dict | None = None            # the target's figures as recorded (HardwareFigures.as_dict())
    target: str = DEFAULT_TARGET

    def value(self, name: str) -> float | None:
        """``accuracy``, or the figure the target's objective or report column ``name`` names (None: not measured)."""
        from snncc.hpo.hardware import hardware_costs, report_columns

        if name == "accuracy":
            return self.accuracy
        objectives = hardware_costs(self.target).objectives
        key = objectives[name].key if name in objectives else report_columns(self.target)[name].key
        v = (self.hardware or {}).get(key)
        return None if v is None else float(v)

    def figures(self, columns: dict[str, Figure]) -> dict[str, object]:
        """The row's figures as stored, by the columns' JSON names (None where not measured)."""
        hw = self.hardware or {}
        return {fig.field or name: hw.get(fig.key) for name, fig in columns.items()}


@dataclass
class HpoReport:
    study: str
    storage: str
    plan: dict
    counts: dict
    rows: list[TrialRow]
    best: dict                   # objective -> trial number
    front: list[int]             # trial numbers on the front (accuracy and ``front_axes``)
    paper_presets: dict
    synthetic_data: bool
    notes: list = field(default_factory=list)
    target: str = DEFAULT_TARGET        # whose hardware figures the trials hold (its columns are the report's)
    columns: dict = field(default_factory=dict)     # name -> Figure (the target's declared report columns)
    front_axes: list = field(default_factory=list)  # the hardware objectives the front weighs beside accuracy

    def as_dict(self) -> dict:
        """The record as plain data; each row also carries its figures by the columns' JSON names."""
        d = asdict(self)
        for row, out in zip(self.rows, d["rows"]):
            out.update(row.figures(self.columns))
        return d

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
        shown_front = [name for name in self.columns if name in self.front_axes]
        best = Table(title="best trial per objective")
        for col in ("objective", "trial", "value", "accuracy %", *(self.columns[n].heading for n in shown_front)):
            best.add_column(col, justify="right")
        for name, number in self.best.items():
            r = self.row(number)
            v = r.value(name)
            if name == "accuracy":
                shown = f"{100 * v:.2f} %"
            else:
                shown = _cell(v, self.columns[name]) if name in self.columns else _num(v)
                shown += " %" if shown != "-" and shown_in_percent(self.columns.get(name)) else ""
            best.add_row(name, str(number), shown, _pct(r.accuracy),
                         *(_cell(r.value(n), self.columns[n]) for n in shown_front))
        console.print(best)
        directions = self._directions()
        axes = " vs ".join(f"{n.replace('_', ' ')} ({directions[n][:3]})" for n in ("accuracy", *self.front_axes))
        console.print(self._table(f"Pareto front: {axes}", [self.row(n) for n in self.front]))
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
        for col in ("trial", "accuracy %", *(f.heading for f in self.columns.values()), "time_bin_size",
                    "nb_input_copies"):
            t.add_column(col, justify="right")
        for r in rows:
            t.add_row(str(r.number) + (" *" if r.paper_preset else ""), _pct(r.accuracy),
                      *(_cell(r.value(n), f) for n, f in self.columns.items()),
                      _g(r.params.get("time_bin_size")), _g(r.params.get("nb_input_copies")))
        return t

    def _directions(self) -> dict[str, str]:
        return directions(self.target)

    def figure(self):
        """Accuracy vs each of the front's first two objectives (the target's declared axes, log where
        declared), the front highlighted: a matplotlib Figure (Agg)."""
        import matplotlib

        matplotlib.use("Agg", force=True)
        import matplotlib.pyplot as plt

        from snncc.hpo.hardware import hardware_costs
        from snncc.log_axis import readable_log_axis

        published = hardware_costs(self.target).published     # a measurement to show beside the trials, if any
        plotted = [n for n in self.front_axes if n in self.columns][:2]
        done = [r for r in self.rows if r.accuracy is not None and all(r.value(n) is not None for n in plotted)]
        front = [r for r in done if r.number in set(self.front)]
        fig, axes = plt.subplots(1, max(1, len(plotted)), figsize=(5.5 * max(1, len(plotted)), 4.2), squeeze=False)
        for ax, name in zip(axes[0], plotted):
            column = self.columns[name]

            def x(r, name=name, column=column):
                return r.value(name) * column.scale

            ax.scatter([x(r) for r in done], [100 * r.accuracy for r in done], s=18, c="0.6", label="trials")
            fr = sorted(front, key=x)
            ax.scatter([x(r) for r in fr], [100 * r.accuracy for r in fr], s=36, c="tab:red",
                       label=f"Pareto front (acc., {', '.join(self.front_axes)})")
            pre = [r for r in done if r.paper_preset]
            if pre:
                ax.scatter([x(r) for r in pre], [100 * r.accuracy for r in pre], marker="*", s=160,
                           c="tab:blue", label="paper's preset, trained here")
            if name in published and "accuracy" in published:
                ax.scatter([published[name]], [published["accuracy"]], marker="D", s=40, c="k",
                           label=str(published.get("label", "published measurement")))
            if column.log:
                readable_log_axis(ax, "x")
            ax.set_xlabel(column.axis or column.heading)
            ax.set_ylabel(f"accuracy % ({self.plan.get('select', 'val')} split)")
            ax.grid(alpha=0.3)
        if plotted:
            axes[0][0].legend(fontsize=7, loc="lower right")
        else:
            axes[0][0].text(0.5, 0.5, f"target {self.target} declares no front to plot", ha="center",
                            transform=axes[0][0].transAxes)
        fig.suptitle(f"snncc hpo: study {self.study} (target {self.target})"
                     + (" -- SYNTHETIC data" if self.synthetic_data else ""), fontsize=10)
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


def shown_in_percent(column: Figure | None) -> bool:
    """A column whose heading ends in % is shown with two decimals (its value x its scale)."""
    return column is not None and column.heading.endswith("%")


def _cell(v, column: Figure) -> str:
    """A figure as a table shows it (``hardware.shown_figure``)."""
    from snncc.hpo.hardware import shown_figure

    return shown_figure(v, column)


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
        row.epochs_run = out.epochs_run
        row.checkpoint, row.worker = out.checkpoint, out.worker
        row.hardware, row.target = dict(hw), out.target
    if t.intermediate_values:
        row.last_intermediate = float(t.intermediate_values[max(t.intermediate_values)])
    elif attrs.get("epoch_metric"):
        row.last_intermediate = float(attrs["epoch_metric"][-1])
    return row


def front_of(rows: list[TrialRow], target: str | None = None) -> list[int]:
    """Numbers of the rows not dominated on accuracy (max) and the front objectives ``target`` declares,
    each in its direction (None: ``hardware.SEARCH_TARGET``; Loihi: energy min, cores min)."""
    from snncc.hpo.hardware import SEARCH_TARGET, front_objectives

    target = target or SEARCH_TARGET
    sign = {name: (-1.0 if d == "maximize" else 1.0) for name, d in directions(target).items()}
    names = ("accuracy", *front_objectives(target))
    ok = [r for r in rows if all(r.value(n) is not None for n in names)]
    ranks = pareto_ranks([tuple(sign[n] * float(r.value(n)) for n in names) for r in ok])
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
    from snncc.hpo.hardware import SEARCH_TARGET, front_objectives, hardware_costs, report_columns

    target = plan_d.get("target") or SEARCH_TARGET
    notes = [f"hardware figures ({target}): {hardware_costs(target).label}"]
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
                     best=best_of(rows, target), front=front_of(rows, target),
                     paper_presets={th: p.as_dict() for th, p in PRESETS.items()}, synthetic_data=synthetic,
                     notes=notes, target=target, columns=report_columns(target),
                     front_axes=list(front_objectives(target)))
