"""``snncc hpo report`` lays out the study's target's columns (its ``hardware`` capability's declaration):
a Xylo study shows neurons, synapses, feasibility, real-time margin and emulated accuracy, and no
empty Loihi column (cores, energy, delay) in its text, its JSON or its front plot."""

from __future__ import annotations

import json

import optuna

from snncc.hpo.outcome import TrialOutcome, parse_objectives
from snncc.hpo.report import study_report
from snncc.hpo.space import SEARCH_SPACE, space_as_dict
from snncc.hpo.study import PLAN_ATTR, StudyPlan
from snncc.training.presets import PRESETS
from tests.hpo.helpers import tiny_args

optuna.logging.set_verbosity(optuna.logging.ERROR)

LOIHI_JSON = ("cores", "synops", "energy_uj", "delay_ms")
LOIHI_TEXT = ("cores", "energy uJ", "uJ", "delay", "synops", "Loihi")   # Xylo's note says "no energy figure"
XYLO_JSON = ("neurons", "output_neurons", "synapses", "feasible", "real_time_margin", "emulated_accuracy")


def _xylo_outcome(acc, neurons, feasible, margin, emulated):
    hw = {"chip": "syns61201", "feasible": feasible, "hidden_neurons": neurons, "output_neurons": 28,
          "synapses": 10 * neurons if feasible else 0, "real_time_margin": margin, "cycles_per_step_worst": 100.0,
          "rule": "direct", "refusal": "" if feasible else "node 'hidden'.reset: refused", "emulated_accuracy": emulated,
          "emulated_on": 4 if emulated is not None else 0}
    return TrialOutcome(params=PRESETS[1].as_dict(), accuracy=acc, selected_on="val", val_accuracy=acc,
                        test_accuracy=acc, best_epoch=1, epochs_run=1, hardware=hw, checkpoint="x.pt",
                        synthetic_data=True, worker="h:1", train_seconds=0.1, target="xylo").as_dict()


def _xylo_report():
    storage = optuna.storages.InMemoryStorage()
    objectives = parse_objectives("pareto", "xylo")
    plan = StudyPlan(name="x", step="anneal", data="d", threshold=1, objectives=objectives, n_trials=4,
                     space=space_as_dict(SEARCH_SPACE), emulate_samples=4, target="xylo")
    study = optuna.create_study(study_name="x", storage=storage, directions=plan.directions)
    study.set_user_attr(PLAN_ATTR, plan.as_dict())
    points = [(0.80, 40, 1, 3.0, 75.0),      # front: most accurate feasible
              (0.60, 24, 1, 5.0, 50.0),      # front: fewest neurons, largest margin
              (0.55, 40, 1, 2.0, 25.0),      # dominated by trial 0 on every axis
              (0.90, 450, 0, 0.0, None)]     # front: most accurate, but the chip cannot hold it
    for acc, n, f, m, e in points:
        values = {"accuracy": acc, "neurons": n, "feasible": f, "real_time_margin": m}
        study.add_trial(optuna.create_trial(values=[values[o] for o in objectives],
                                            user_attrs={"outcome": _xylo_outcome(acc, n, f, m, e)}))
    return study_report(storage, "x", "memory")


def test_pareto_of_a_xylo_study_is_accuracy_and_the_front_xylo_declares():
    assert parse_objectives("pareto", "xylo") == ("accuracy", "neurons", "real_time_margin", "feasible")
    assert parse_objectives("pareto") == ("accuracy", "energy", "cores")


def test_xylo_report_front_best_text_and_json_carry_xylos_figures():
    from rich.console import Console

    rep = _xylo_report()
    assert rep.target == "xylo" and rep.front_axes == ["neurons", "real_time_margin", "feasible"]
    assert rep.front == [0, 1, 3]                            # margin and feasibility maximised, neurons minimised
    assert rep.best == {"accuracy": 3, "neurons": 1, "feasible": 0, "real_time_margin": 1, "emulated_accuracy": 0}
    console = Console(width=250, record=True)
    rep.render_text(console)
    text = console.export_text()
    for heading in ("hidden neurons", "synapses", "feasible (1/0)", "real-time margin (EST.)", "emulated %"):
        assert heading in text, heading
    assert "75.00 %" in text and "75.00" in text            # emulated accuracy is stored in % on Xylo: not x 100
    assert "7500" not in text
    for word in LOIHI_TEXT:
        assert word not in text, word
    assert "accuracy (max) vs neurons (min) vs real time margin (max) vs feasible (max)" in text
    d = json.loads(json.dumps(rep.as_dict()))
    rows = {r["number"]: r for r in d["rows"]}
    assert rows[1]["neurons"] == 24 and rows[1]["synapses"] == 240 and rows[1]["real_time_margin"] == 5.0
    assert rows[3]["feasible"] == 0 and rows[3]["emulated_accuracy"] is None
    assert all(set(XYLO_JSON) <= set(r) and not set(LOIHI_JSON) & set(r) for r in d["rows"])
    assert set(d["columns"]) == {"neurons", "output_neurons", "synapses", "feasible", "real_time_margin",
                                 "emulated_accuracy"}


def test_xylo_front_plot_is_accuracy_vs_neurons_and_real_time_margin(tmp_path):
    import matplotlib.pyplot as plt

    rep = _xylo_report()
    fig = rep.figure()
    try:
        labels = [ax.get_xlabel() for ax in fig.axes]
        assert labels[0] == "hidden neurons" and labels[1].startswith("real-time margin") and len(labels) == 2
        assert all(ax.get_xscale() == "linear" for ax in fig.axes)
        assert "target xylo" in fig._suptitle.get_text()
        trials, front = (c.get_offsets() for c in fig.axes[0].collections[:2])
        assert sorted(trials[:, 0].tolist()) == [24, 40, 40, 450] and sorted(front[:, 0].tolist()) == [24, 40, 450]
        assert sorted(fig.axes[1].collections[1].get_offsets()[:, 0].tolist()) == [0.0, 3.0, 5.0]
        legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
        assert "Pareto front (acc., neurons, real_time_margin, feasible)" in legend
        assert not any("paper" in t or "Loihi" in t for t in legend)     # Xylo publishes no measurement
    finally:
        plt.close(fig)
    assert rep.plot(tmp_path / "x.png").read_bytes()[:4] == b"\x89PNG"


def test_loihi_front_plot_keeps_energy_and_cores():
    import matplotlib.pyplot as plt

    from tests.hpo.test_report import _report_with_energies

    rep = _report_with_energies((5.0, 10.0, 11.0))
    fig = rep.figure()
    try:
        assert [ax.get_xlabel() for ax in fig.axes] == ["energy per sample, uJ (ESTIMATE)", "Loihi cores"]
        legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
        assert "paper: measured on Loihi (real data, th 1)" in legend
    finally:
        plt.close(fig)
    rows = rep.as_dict()["rows"]
    assert all(r["cores"] >= 1 and r["energy_uj"] > 0 and r["delay_ms"] > 0 and "neurons" not in r for r in rows)


def test_a_tiny_xylo_study_reports_its_figures_from_the_command_line(braille_dir, tmp_path, capsys):
    """``hpo run --target xylo`` (2 trials, 1 epoch, 8 hidden neurons) then ``hpo report``: text, JSON, figure."""
    from snncc.cli.main import run as cli

    work = tmp_path / "w"
    args = ["hpo", "run", "xs", "--step", "anneal", "--trials", "2", "--epochs", "1", "--target", "xylo",
            "--objectives", "accuracy,neurons,feasible", "--emulate", "2", *tiny_args(braille_dir, work)]
    assert cli(args) == 0
    capsys.readouterr()
    assert cli(["hpo", "report", "xs", "--dir", str(work), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["target"] == "xylo" and rep["counts"]["complete"] == 2 and rep["front"]
    for row in rep["rows"]:
        assert row["neurons"] == 8 and row["output_neurons"] == 28 and row["feasible"] in (0, 1)
        assert set(XYLO_JSON) <= set(row) and not set(LOIHI_JSON) & set(row)
    assert (work / "xs-front.png").read_bytes()[:4] == b"\x89PNG"
    assert cli(["hpo", "report", "xs", "--dir", str(work), "--no-plot"]) == 0
    text = capsys.readouterr().out
    assert "hidden neurons" in text and "real-time margin" in text and "feasible" in text
    for word in LOIHI_TEXT:
        assert word not in text, word


def test_a_xylo_study_compiles_each_trial_with_the_target_options_it_was_given(braille_dir, tmp_path, capsys):
    """``hpo run --target xylo --chip syns65302 --allow-reset-change``: the options are stored with the plan
    and every trial is lowered with them (here Xylo Audio 3, whose 16 input channels cannot hold the Braille
    RSNN's 24: the trial is recorded infeasible with that rule's line, not the reset's)."""
    from snncc.cli.main import run as cli
    from snncc.hpo.storage import default_url, open_storage
    from snncc.hpo.study import load_study, stored_plan

    work = tmp_path / "w"
    base = ["hpo", "run", "xo", "--step", "anneal", "--trials", "1", "--epochs", "1", "--target", "xylo",
            "--objectives", "accuracy,feasible", *tiny_args(braille_dir, work)]
    assert cli([*base, "--chip", "syns65302", "--allow-reset-change", "--json"]) == 0
    capsys.readouterr()
    assert cli(["hpo", "report", "xo", "--dir", str(work), "--json", "--no-plot"]) == 0
    (row,) = json.loads(capsys.readouterr().out)["rows"]
    hw = row["hardware"]
    assert hw["chip"] == "syns65302" and hw["feasible"] == 0
    assert "Xylo Audio 3 has 16" in hw["refusal"] and "reset" not in hw["refusal"]
    plan = stored_plan(load_study(open_storage(default_url(work), 1), "xo"))
    assert plan.target_options == {"chip": "syns65302", "allow_reset_change": True}


def test_hpo_run_refuses_a_target_option_its_target_does_not_take(braille_dir, tmp_path, capsys):
    from snncc.cli.main import run as cli

    work = tmp_path / "w"
    args = ["hpo", "run", "xr", "--step", "anneal", "--trials", "1", "--epochs", "1", "--target", "xylo",
            "--scale", "global", *tiny_args(braille_dir, work)]
    assert cli(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("snncc: error: ") and "--scale" in err[0] and "xylo" in err[0]
    assert not work.exists()
