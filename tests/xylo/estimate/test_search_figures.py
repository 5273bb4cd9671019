"""Xylo's ``hardware`` capability (what snncc hpo costs a trial with): neurons, feasibility, real-time margin."""

import numpy as np
import torch

from snncc.frontends import graph_from_object
from snncc.frontends.checkpoint import save_checkpoint
from snncc.hpo.hardware import hardware_figures
from snncc.models import SNNConfig, SpikingClassifier
from snncc.targets import capability, get_target

QUICK = {"rule": "direct", "calibration_samples": 8, "time_steps": 32, "allow_reset_change": True}


def small_rsnn(n_hidden=24):
    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_inputs=12, input_copies=1, n_hidden=n_hidden, n_outputs=7, order="loihi"))
    model.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.2)
    return model


def test_objectives_name_keys_of_the_figures():
    costs = capability(get_target("xylo"), "hardware")()
    assert set(costs.objectives) == {"neurons", "feasible", "real_time_margin", "emulated_accuracy"}
    assert dict(costs.published) == {} and "ESTIMATE" in costs.label
    g = graph_from_object(small_rsnn())
    x = (np.random.default_rng(0).random((6, 32, 12)) < 0.2).astype(np.uint8)
    y = np.arange(6) % 7
    fig = costs.figures(g, x, y, QUICK, emulate_samples=6).as_dict()
    for objective in costs.objectives.values():
        assert objective.key in fig
    assert fig["feasible"] == 1 and fig["hidden_neurons"] == 24 and fig["output_neurons"] == 7
    assert fig["real_time_margin"] > 1 and fig["synapses"] > 0 and fig["emulated_on"] == 6
    assert 0 <= fig["emulated_accuracy"] <= 100


def test_a_model_the_chip_cannot_hold_is_infeasible_not_an_error(tmp_path):
    path = tmp_path / "rsnn.pt"
    save_checkpoint(small_rsnn(), path, {"dt": 0.005})       # resets to zero: refused without the change allowed
    x = np.zeros((2, 16, 12), np.uint8)
    fig = hardware_figures(path, x, np.zeros(2, int), target="xylo").as_dict()
    assert fig["feasible"] == 0 and "reset" in fig["refusal"] and fig["hidden_neurons"] == 24
    costs = capability(get_target("xylo"), "hardware")()
    big = costs.figures(graph_from_object(small_rsnn(n_hidden=130)), x, np.zeros(2, int),
                        dict(QUICK, chip="syns63300")).as_dict()
    assert big["feasible"] == 0 and "128" in big["refusal"] and big["chip"] == "syns63300"


def test_a_study_takes_the_xylo_targets_objectives():
    import pytest

    from snncc.errors import SnnccError
    from snncc.hpo.outcome import TrialOutcome, directions, parse_objectives
    from snncc.hpo.study import StudyPlan

    assert parse_objectives("accuracy,feasible,real_time_margin", "xylo") == ("accuracy", "feasible", "real_time_margin")
    assert directions("xylo")["neurons"] == "minimize" and directions()["energy"] == "minimize"   # default: Loihi
    with pytest.raises(SnnccError, match="unknown objective 'energy'"):
        parse_objectives("accuracy,energy", "xylo")
    plan = StudyPlan(name="s", step="anneal", data="d", threshold=1, objectives=("accuracy", "neurons"), target="xylo")
    assert plan.directions == ["maximize", "minimize"]
    assert StudyPlan.from_dict({k: v for k, v in plan.as_dict().items() if k != "target"}).target == "loihi"
    out = TrialOutcome(params={}, accuracy=0.5, selected_on="val", val_accuracy=0.5, test_accuracy=0.5, best_epoch=1,
                       epochs_run=1, hardware={"hidden_neurons": 24, "feasible": 1}, checkpoint="c",
                       synthetic_data=True, worker="w", train_seconds=0.0, target="xylo")
    assert out.value("neurons") == 24 and out.value("feasible") == 1


def test_the_report_reads_a_xylo_studys_figures():
    from snncc.hpo.report import TrialRow, best_of

    rows = [TrialRow(number=k, state="COMPLETE", params={}, accuracy=acc, target="xylo",
                     hardware={"hidden_neurons": n, "feasible": f, "real_time_margin": m})
            for k, (acc, n, f, m) in enumerate([(0.6, 40, 1, 3.0), (0.7, 450, 0, 0.0), (0.5, 24, 1, 5.0)])]
    assert rows[0].value("neurons") == 40 and rows[1].value("feasible") == 0
    assert best_of(rows, "xylo") == {"accuracy": 1, "neurons": 2, "feasible": 0, "real_time_margin": 2}
