"""The report from stored trials: best per objective, the (accuracy, energy, cores) front, labels."""

from __future__ import annotations

import optuna

from snncc.hpo.outcome import TrialOutcome
from snncc.hpo.report import study_report
from snncc.hpo.space import SEARCH_SPACE, space_as_dict
from snncc.hpo.study import PLAN_ATTR, StudyPlan
from snncc.training.presets import PRESETS

optuna.logging.set_verbosity(optuna.logging.ERROR)


def _outcome(acc, energy, cores, select="test"):
    hw = {"cores": cores, "chips": 1, "synaptic_ops_per_sample": energy * 1e4, "spikes_per_sample": 1.0,
          "energy_uj_per_sample": energy, "delay_ms_per_sample": energy / 10, "t_sample": 270, "estimated_on": 4,
          "emulated_accuracy": None}
    return TrialOutcome(params=PRESETS[1].as_dict(), accuracy=acc, selected_on=select, val_accuracy=None,
                        test_accuracy=acc, best_epoch=1, epochs_run=1, hardware=hw, checkpoint="x.pt",
                        synthetic_data=True, worker="h:1", train_seconds=0.1).as_dict()


def test_front_best_and_labels(tmp_path):
    storage = optuna.storages.InMemoryStorage()
    plan = StudyPlan(name="r", step="anneal", data="d", threshold=1, objectives=("accuracy", "energy", "cores"),
                     n_trials=5, space=space_as_dict(SEARCH_SPACE), select="test")
    study = optuna.create_study(study_name="r", storage=storage, directions=plan.directions)
    study.set_user_attr(PLAN_ATTR, plan.as_dict())
    points = [(0.80, 10.0, 4), (0.70, 5.0, 4), (0.75, 12.0, 2), (0.60, 11.0, 5)]   # the last is dominated
    for acc, energy, cores in points:
        study.add_trial(optuna.create_trial(values=[acc, energy, cores], user_attrs={"outcome": _outcome(acc, energy, cores)}))
    study.add_trial(optuna.create_trial(state=optuna.trial.TrialState.FAIL, user_attrs={"error": "d: x: too big"}))
    rep = study_report(storage, "r", "memory")
    assert rep.front == [0, 1, 2]
    assert rep.best["accuracy"] == 0 and rep.best["energy"] == 1 and rep.best["cores"] == 2
    assert rep.counts["complete"] == 4 and rep.counts["failed"] == 1
    assert rep.synthetic_data and any("optimistic" in n for n in rep.notes) and any("ESTIMATE" in n for n in rep.notes)
    assert rep.row(4).error == "d: x: too big"
    path = rep.plot(tmp_path / "f.png")
    assert path.read_bytes()[:4] == b"\x89PNG" and not list(tmp_path.glob(".*part"))


def _report_with_energies(energies):
    storage = optuna.storages.InMemoryStorage()
    plan = StudyPlan(name="e", step="anneal", data="d", threshold=1, objectives=("accuracy", "energy", "cores"),
                     n_trials=len(energies), space=space_as_dict(SEARCH_SPACE), select="test")
    study = optuna.create_study(study_name="e", storage=storage, directions=plan.directions)
    study.set_user_attr(PLAN_ATTR, plan.as_dict())
    for i, energy in enumerate(energies):
        acc, cores = 0.5 + 0.04 * i, 2 + i
        study.add_trial(optuna.create_trial(values=[acc, energy, cores], user_attrs={"outcome": _outcome(acc, energy, cores)}))
    return study_report(storage, "e", "memory")


import pytest  # noqa: E402


@pytest.mark.parametrize("energies", [(5.0, 10.0, 11.0, 12.0),          # with the paper's 71 uJ: ~1 decade
                                      (60.0, 65.0, 80.0),               # a fraction of a decade
                                      (0.3, 4.0, 900.0, 20000.0)])      # five decades
def test_front_plot_energy_axis_labels_do_not_overlap(energies):
    """The log axis's tick labels are plain numbers and no two labels' rendered boxes overlap."""
    import matplotlib.pyplot as plt

    from snncc.log_axis import overlapping_labels

    fig = _report_with_energies(energies).figure()
    try:
        energy_axis = fig.axes[0]
        assert energy_axis.get_xscale() == "log"
        assert overlapping_labels(energy_axis, "x") == []
        low, high = energy_axis.get_xlim()
        shown = [t.get_text() for t, x in zip(energy_axis.get_xticklabels(), energy_axis.get_xticks())
                 if t.get_text() and low <= x <= high]
        assert len(shown) >= 2 and all("times" not in t and "^" not in t for t in shown), shown
        for text in shown:
            float(text)                      # plain numbers
    finally:
        plt.close(fig)


def test_overlap_detector_sees_matplotlibs_default_log_labels_collide():
    """The check above can fail: matplotlib's own log labels over ~1 decade on a narrow axis collide."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    from snncc.log_axis import overlapping_labels

    fig, ax = plt.subplots(figsize=(2.0, 3.0))
    ax.scatter([5, 10, 12, 71], [1, 2, 3, 4])
    ax.set_xscale("log")
    try:
        assert overlapping_labels(ax, "x")
    finally:
        plt.close(fig)
