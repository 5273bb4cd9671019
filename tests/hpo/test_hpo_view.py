"""``snncc hpo run``'s bars (``snncc.cli.hpo_view``): the search's ``StudyView`` drawn on a console."""

from __future__ import annotations

import io
from types import SimpleNamespace

from rich.console import Console

from snncc.cli.hpo_view import RichStudyView
from snncc.hpo.progress import StudyView


def test_rich_view_draws_each_study_and_prints_one_line_per_trial():
    buf = io.StringIO()
    view = RichStudyView(Console(file=buf, width=200, force_terminal=False))
    assert isinstance(view, StudyView)
    view.trial_epoch(SimpleNamespace(epoch=1), 0.5)          # before a study: nothing to draw on, no error
    budget = SimpleNamespace(n_trials=2, spent=1, complete=1, pruned=0, running=0)
    for study in ("s", "s-grid"):                              # a fresh pair of bars per step
        view.study_start(study)
        assert view.progress.tasks[0].description == f"study {study}"
        view.study_update(budget)
        view.trial_start(3, 2, {})
        view.trial_epoch(SimpleNamespace(epoch=1), 0.25)
        assert view.progress.tasks[1].completed == 1 and "accuracy 25.0 %" in view.progress.tasks[1].description
        view.trial_done(3, SimpleNamespace(accuracy=0.25, selected_on="val", target="loihi",
                                           hardware={"cores": 2, "synaptic_ops_per_sample": 1000,
                                                     "energy_uj_per_sample": 1.5}))
        view.trial_done(5, SimpleNamespace(accuracy=0.5, selected_on="val", target="xylo",
                                           hardware={"hidden_neurons": 8, "output_neurons": 28, "synapses": 0,
                                                     "feasible": 0, "real_time_margin": 0.0, "emulated_accuracy": None}))
        view.trial_error(4, "x.py: boom")
        view.close()
        assert view.progress is None
    out = buf.getvalue()
    assert out.count("trial 3: accuracy 25.00 % (val); loihi: cores 2, synops/sample 1,000, energy uJ (EST.) 1.5\n") == 2
    assert out.count("trial 5: accuracy 50.00 % (val); xylo: hidden neurons 8, output neurons 28, synapses 0, "
                     "feasible (1/0) 0, real-time margin (EST.) 0\n") == 2     # each target's own figures
    assert out.count("trial 4 failed: x.py: boom") == 2
