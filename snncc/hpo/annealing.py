"""Step 1's tuner: an annealing sampler for Optuna, with the paper's evenly spaced re-initialisations.

The paper ran NNI's *Anneal* tuner (hyperopt's annealing): start from the prior, then sample
ever closer to the good trials seen so far. The rule, per new trial number ``t``:

* **segment**: trials since the last re-initialisation (``restarts``: trial numbers where the tuner
  starts afresh; ``evenly_spaced_restarts(n, 2)`` gives the paper's two, at n/3 and 2n/3). Only
  COMPLETE trials of the current segment with a number below ``t`` are seen.
* **prior**: while fewer than ``n_startup`` trials are seen, every value is drawn uniformly (in
  log space for log ranges) -- a re-initialisation therefore forgets everything before it.
* **anchor**: otherwise the seen trials are ranked (best value first; several objectives: by
  non-domination rank, then the first objective) and the anchor is rank ``k`` with ``k`` drawn
  geometrically with mean ``avg_best_idx`` (clipped to the list).
* **neighbourhood**: each value is drawn around the anchor's, with a width that shrinks as the
  segment grows: ``w = 1 / (1 + shrink * n_seen)``. Numbers: normal with standard deviation
  ``w x (high - low)`` (log space for log ranges), redrawn up to 8 times when outside the range,
  then clipped, rounded to the step for integers. Categories: a uniform draw with probability
  ``w``, else the anchor's.

Everything is derived from the storage and from RNGs seeded by ``(seed, trial number, name)``,
so a resumed study, or one shared by several workers, samples as one uninterrupted process would.
"""

from __future__ import annotations

import math
import zlib
from typing import Sequence

import numpy as np

from optuna.distributions import CategoricalDistribution, IntDistribution
from optuna.samplers import BaseSampler
from optuna.study import StudyDirection
from optuna.trial import TrialState


def evenly_spaced_restarts(n_trials: int, k: int = 2) -> tuple[int, ...]:
    """Trial numbers of ``k`` evenly spaced re-initialisations in a budget of ``n_trials`` (2: n/3, 2n/3)."""
    if n_trials < 1 or k < 0:
        return ()
    points = sorted({int(round(n_trials * (i + 1) / (k + 1))) for i in range(k)})
    return tuple(p for p in points if 0 < p < n_trials)


def dominates(a: Sequence[float], b: Sequence[float]) -> bool:
    """``a`` at least as good as ``b`` everywhere and better somewhere (values already 'lower is better')."""
    return all(x <= y for x, y in zip(a, b)) and any(x < y for x, y in zip(a, b))


def pareto_ranks(points: Sequence[Sequence[float]]) -> list[int]:
    """Non-domination rank of each point (0 = on the front), lower is better in every coordinate."""
    remaining = set(range(len(points)))
    ranks = [0] * len(points)
    rank = 0
    while remaining:
        front = {i for i in remaining if not any(dominates(points[j], points[i]) for j in remaining if j != i)}
        for i in front:
            ranks[i] = rank
        remaining -= front
        rank += 1
    return ranks


class AnnealingSampler(BaseSampler):
    """Hyperopt-style annealing with re-initialisations at fixed trial numbers (see the module doc)."""

    def __init__(self, restarts: Sequence[int] = (), n_startup: int = 1, shrink: float = 0.1,
                 avg_best_idx: float = 2.0, seed: int = 0):
        if n_startup < 1 or shrink < 0 or avg_best_idx < 1:
            raise ValueError("need n_startup >= 1, shrink >= 0, avg_best_idx >= 1")
        self.restarts = tuple(sorted(int(r) for r in restarts))
        self.n_startup = int(n_startup)
        self.shrink = float(shrink)
        self.avg_best_idx = float(avg_best_idx)
        self.seed = int(seed)
        self._anchors: dict[int, tuple[dict | None, int]] = {}

    # -- the rule ---------------------------------------------------------------------------------
    def segment_start(self, number: int) -> int:
        """Trial number where ``number``'s segment begins (the last re-initialisation at or before it)."""
        return max([0] + [r for r in self.restarts if r <= number])

    def seen(self, study, number: int) -> list:
        """COMPLETE trials of ``number``'s segment with a smaller number (what the tuner knows)."""
        start = self.segment_start(number)
        return [t for t in study._storage.get_all_trials(study._study_id, deepcopy=False, states=(TrialState.COMPLETE,))
                if start <= t.number < number and t.values is not None]

    def ranked(self, study, trials: list) -> list:
        """``trials`` best first (several objectives: non-domination rank, then the first objective)."""
        signs = [(-1.0 if d == StudyDirection.MAXIMIZE else 1.0) for d in study.directions]
        keyed = [[s * v for s, v in zip(signs, t.values)] for t in trials]
        ranks = pareto_ranks(keyed) if len(signs) > 1 else [0] * len(trials)
        order = sorted(range(len(trials)), key=lambda i: (ranks[i], keyed[i][0], trials[i].number))
        return [trials[i] for i in order]

    def anchor(self, study, trial) -> tuple[dict | None, int]:
        """(anchor params or None for the prior, number of trials seen) for ``trial`` (cached per trial)."""
        if trial._trial_id in self._anchors:
            return self._anchors[trial._trial_id]
        seen = self.seen(study, trial.number)
        if len(seen) < self.n_startup:
            result = (None, len(seen))
        else:
            rng = np.random.default_rng([self.seed, trial.number, 0])
            k = min(len(seen) - 1, int(rng.geometric(1.0 / self.avg_best_idx)) - 1)
            result = (dict(self.ranked(study, seen)[k].params), len(seen))
        self._anchors[trial._trial_id] = result
        return result

    def width(self, n_seen: int) -> float:
        return 1.0 / (1.0 + self.shrink * n_seen)

    # -- Optuna's sampler interface ---------------------------------------------------------------
    def infer_relative_search_space(self, study, trial):
        return {}

    def sample_relative(self, study, trial, search_space):
        return {}

    def sample_independent(self, study, trial, param_name, param_distribution):
        rng = np.random.default_rng([self.seed, trial.number, zlib.crc32(param_name.encode()) + 1])
        anchor, n_seen = self.anchor(study, trial)
        if anchor is None or param_name not in anchor:
            return _prior(param_distribution, rng)
        return _near(param_distribution, anchor[param_name], self.width(n_seen), rng)

    def after_trial(self, study, trial, state, values):
        self._anchors.pop(trial._trial_id, None)

    def reseed_rng(self) -> None:  # draws depend on (seed, trial number, name) only
        pass


def _bounds(dist) -> tuple[float, float, bool]:
    return float(dist.low), float(dist.high), bool(getattr(dist, "log", False))


def _to_internal(x: float, log: bool) -> float:
    return math.log(x) if log else x


def _from_internal(z: float, log: bool) -> float:
    return math.exp(z) if log else z


def _finish(dist, x: float):
    low, high, _ = _bounds(dist)
    x = min(max(x, low), high)
    step = getattr(dist, "step", None)
    if isinstance(dist, IntDistribution):
        step = step or 1
        return int(min(max(low + round((x - low) / step) * step, low), high))
    if step is not None:
        x = low + round((x - low) / step) * step
        return float(min(max(x, low), high))
    return float(x)


def _prior(dist, rng: np.random.Generator):
    if isinstance(dist, CategoricalDistribution):
        return dist.choices[int(rng.integers(len(dist.choices)))]
    low, high, log = _bounds(dist)
    if isinstance(dist, IntDistribution) and not log:   # every integer equally likely
        return _finish(dist, low + rng.uniform(0, high - low + 1) - 0.5)
    lo, hi = _to_internal(low, log), _to_internal(high + (0.5 if isinstance(dist, IntDistribution) else 0.0), log)
    return _finish(dist, _from_internal(rng.uniform(lo, hi), log))


def _near(dist, value, width: float, rng: np.random.Generator):
    if isinstance(dist, CategoricalDistribution):
        if value not in dist.choices or rng.random() < width:
            return dist.choices[int(rng.integers(len(dist.choices)))]
        return value
    low, high, log = _bounds(dist)
    lo, hi = _to_internal(low, log), _to_internal(high, log)
    centre = _to_internal(min(max(float(value), low), high), log)
    sigma = width * (hi - lo)
    if sigma <= 0:
        return _finish(dist, float(value))
    z = centre
    for _ in range(8):
        z = rng.normal(centre, sigma)
        if lo <= z <= hi:
            break
    return _finish(dist, _from_internal(min(max(z, lo), hi), log))


__all__ = ["AnnealingSampler", "evenly_spaced_restarts", "pareto_ranks", "dominates"]
