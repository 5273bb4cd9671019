"""The annealing sampler: the paper's re-initialisations, determinism, resumption, convergence."""

from __future__ import annotations

import math

import numpy as np
import optuna
import pytest

from snncc.hpo.annealing import AnnealingSampler, evenly_spaced_restarts, pareto_ranks

optuna.logging.set_verbosity(optuna.logging.ERROR)


def toy(trial):
    x = trial.suggest_float("x", 0.0, 1.0)
    y = trial.suggest_float("y", 1e-4, 1.0, log=True)
    k = trial.suggest_int("k", 1, 16, log=True)
    c = trial.suggest_categorical("c", ["a", "b", "c"])
    return (x - 0.3) ** 2 + (math.log10(y) + 2) ** 2 / 16 + (k - 4) ** 2 / 100 + (c != "b") * 0.05


def _study(sampler, storage=None, name="toy", directions=("minimize",)):
    return optuna.create_study(sampler=sampler, storage=storage, study_name=name, directions=list(directions),
                               load_if_exists=True)


def test_evenly_spaced_restarts_are_the_papers_two():
    assert evenly_spaced_restarts(600, 2) == (200, 400)
    assert evenly_spaced_restarts(9) == (3, 6)
    assert evenly_spaced_restarts(2) == (1,)        # 2/3 and 4/3 round to 1 and 1
    assert evenly_spaced_restarts(10, 0) == ()


def test_pareto_ranks():
    pts = [(0, 1), (1, 0), (1, 1), (2, 2), (0.5, 0.5)]
    assert pareto_ranks(pts) == [0, 0, 1, 2, 0]


def test_a_reinitialisation_forgets_everything_before_it():
    sampler = AnnealingSampler(restarts=(10, 20), n_startup=2, seed=1)
    study = _study(sampler)
    study.optimize(toy, n_trials=25)
    numbers = lambda ts: sorted(t.number for t in ts)  # noqa: E731
    assert numbers(sampler.seen(study, 10)) == []
    assert numbers(sampler.seen(study, 11)) == [10]
    assert numbers(sampler.seen(study, 24)) == [20, 21, 22, 23]
    assert numbers(sampler.seen(study, 9)) == list(range(9))
    # right after a restart the values come from the prior: they do not follow the segment's best
    frozen = {t.number: t for t in study.trials}
    assert sampler.segment_start(10) == 10 and sampler.segment_start(19) == 10 and sampler.segment_start(25) == 20
    for n in (10, 11, 20, 21):   # fewer than n_startup seen -> prior (anchor None)
        sampler._anchors.clear()
        assert sampler.anchor(study, frozen[n])[0] is None


def test_same_seed_same_trials_and_resuming_samples_as_one_run():
    url = optuna.storages.InMemoryStorage()     # a second sampler object on it stands for a new process
    one = _study(AnnealingSampler(restarts=(6,), seed=3))
    one.optimize(toy, n_trials=12)
    first = _study(AnnealingSampler(restarts=(6,), seed=3), storage=url)
    first.optimize(toy, n_trials=5)
    resumed = _study(AnnealingSampler(restarts=(6,), seed=3), storage=url)   # a new process, same storage
    resumed.optimize(toy, n_trials=7)
    assert [t.params for t in one.trials] == [t.params for t in resumed.trials]
    other = _study(AnnealingSampler(restarts=(6,), seed=4))
    other.optimize(toy, n_trials=3)
    assert [t.params for t in other.trials] != [t.params for t in one.trials[:3]]


def test_values_stay_in_range_and_typed():
    study = _study(AnnealingSampler(seed=0))
    study.optimize(toy, n_trials=30)
    for t in study.trials:
        p = t.params
        assert 0 <= p["x"] <= 1 and 1e-4 <= p["y"] <= 1 and 1 <= p["k"] <= 16 and isinstance(p["k"], int)
        assert p["c"] in ("a", "b", "c")


def test_annealing_narrows_and_beats_random_search():
    gaps, spreads = [], []
    for seed in range(3):
        anneal = _study(AnnealingSampler(seed=seed, n_startup=3))
        anneal.optimize(toy, n_trials=60)
        rand = _study(optuna.samplers.RandomSampler(seed=seed))
        rand.optimize(toy, n_trials=60)
        gaps.append(rand.best_value - anneal.best_value)
        xs = np.array([t.params["x"] for t in anneal.trials])
        spreads.append((xs[:15].std(), xs[-15:].std()))
    assert np.mean(gaps) > 0
    assert all(late < early for early, late in spreads)


def test_several_objectives_anchor_on_the_front():
    def two(trial):
        x = trial.suggest_float("x", 0, 1)
        return x, (1 - x) ** 2

    sampler = AnnealingSampler(seed=0, n_startup=2)
    study = _study(sampler, directions=("minimize", "minimize"))
    study.optimize(two, n_trials=15)
    seen = sampler.seen(study, 15)
    ranked = sampler.ranked(study, seen)
    front = {t.number for t in study.best_trials}
    assert ranked[0].number in front


def test_bad_settings_are_refused():
    with pytest.raises(ValueError):
        AnnealingSampler(n_startup=0)
