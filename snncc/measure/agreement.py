"""Argmax agreement of a target with the float model, with its sample count and 95 % interval.

Rule for samples without a single float winner: a sample whose float score has a tie at the top
(two or more classes share the maximum) or, for a spiking readout, whose float output is silent
(every count 0), has no decision to agree with. Such samples are left out of the argmax figure
and counted beside it (``ties``, ``silent``). Over the n decided samples, k agree when the
target's argmax (ties to the lowest index, as the readout) equals the float one; the share k/n
is given with its 95 % Wilson score interval (z = 1.959964):

    centre = (p + z^2/2n) / (1 + z^2/n),   half = z/(1 + z^2/n) * sqrt(p(1 - p)/n + z^2/4n^2)

With no decided sample the agreement is undefined (None, "undefined: outputs silent"), never 100 %.
``DEFAULT_SAMPLES`` = 1,000 keeps the interval within about +-0.03 whatever the share
(half-width <= 1.96 * sqrt(0.25 / 1000) = 0.031). A model whose float run costs more than
``LARGE_MODEL_NEURON_STEPS`` neuron-steps per sample (its populations' neurons x steps; e.g. the
Sinabs N-MNIST CNN, ~9,000 neurons x 100 steps) defaults to ``LARGE_MODEL_SAMPLES`` = 200 instead
(half-width <= 0.07), so the default check stays within a minute or two of CPU time
(``default_samples``); --limit sets any count.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

Z95 = 1.959964
DEFAULT_SAMPLES = 1000
LARGE_MODEL_NEURON_STEPS = 200_000
LARGE_MODEL_SAMPLES = 200
UNDECIDED_RULE = ("samples whose float output has no single winner (a tie at the top, or silence) are left out "
                  "of the argmax figure and counted beside it")


CHUNK_NEURON_STEPS = 1 << 24    # neuron-steps simulated at once: bounds the float reference's memory


def chunk_size(neurons: int, steps: int, most: int = 64) -> int:
    """Samples to simulate at once so one chunk stays within ``CHUNK_NEURON_STEPS`` (at most ``most``)."""
    return int(max(1, min(most, CHUNK_NEURON_STEPS // max(1, int(neurons) * int(steps)))))


def default_samples(neurons: int, steps: int) -> int:
    """The default sample count for a model of ``neurons`` spiking neurons run ``steps`` steps per sample."""
    return LARGE_MODEL_SAMPLES if int(neurons) * int(steps) > LARGE_MODEL_NEURON_STEPS else DEFAULT_SAMPLES


def default_samples_note(samples: int) -> str:
    """What the report says about a default sample count."""
    if samples == DEFAULT_SAMPLES:
        return f"{samples} samples (the default: a 95 % interval of about +-0.03)"
    return (f"{samples} samples (the default for a model of more than {LARGE_MODEL_NEURON_STEPS:,} neuron-steps per "
            "sample: a 95 % interval of about +-0.07; --limit sets more)")


def wilson_interval(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of k successes in n trials (n >= 1)."""
    if n < 1:
        raise ValueError("the interval needs n >= 1")
    p = k / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z / denom * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    low = 0.0 if k == 0 else max(0.0, centre - half)      # the exact endpoints (no rounding residue)
    high = 1.0 if k == n else min(1.0, centre + half)
    return low, high


@dataclass
class ArgmaxAgreement:
    """k of n decided samples agree; ties and silent samples are counted beside, not in, the figure."""

    samples: int                 # all samples compared
    decided: int                 # n: samples with a single float winner
    agreeing: int                # k
    ties: int                    # float output tied at the top (not silent)
    silent: int                  # float output silent (spiking readouts only)
    share: float | None          # k / n, None when n = 0 (undefined)
    low: float | None            # 95 % Wilson interval
    high: float | None

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def defined(self) -> bool:
        return self.share is not None

    def text(self) -> str:
        if not self.defined:
            why = "outputs silent" if self.silent == self.samples else "no sample has a single float winner"
            return f"undefined: {why} ({self.silent} silent, {self.ties} tied of {self.samples} samples)"
        aside = []
        if self.ties:
            aside.append(f"{self.ties} tied")
        if self.silent:
            aside.append(f"{self.silent} silent")
        beside = f"; left out: {', '.join(aside)}" if aside else ""
        return (f"{self.share:.3f} [{self.low:.3f}, {self.high:.3f}] (95 %), {self.agreeing} of {self.decided} "
                f"decided samples{beside}")


def undecided(scores: np.ndarray, spiking: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(tied, silent) masks over the samples of ``scores`` (B, classes): silent = every score 0 (spiking
    readouts only); tied = the maximum shared by two or more classes (silent samples excluded)."""
    s = np.asarray(scores, np.float64)
    top = s.max(axis=1, keepdims=True)
    silent = np.all(s == 0, axis=1) if spiking else np.zeros(s.shape[0], bool)
    tied = (np.sum(s == top, axis=1) > 1) & ~silent
    return tied, silent


def decided(scores: np.ndarray, spiking: bool = True) -> np.ndarray:
    """(B,) bool: the samples of ``scores`` (B, classes) with a single winner (neither tied nor silent)."""
    tied, silent = undecided(scores, spiking)
    return ~(tied | silent)


def argmax_hits(reference: np.ndarray, target: np.ndarray, spiking: bool = True) -> np.ndarray:
    """(decided,) bool: per decided sample of ``reference``, whether ``target``'s argmax equals it (the
    per-sample form of ``argmax_agreement``, for paired comparisons)."""
    ref, got = np.asarray(reference), np.asarray(target)
    keep = decided(ref, spiking)
    return (np.argmax(ref, axis=1) == np.argmax(got, axis=1))[keep]


def sign_test(better: int, worse: int) -> float:
    """One-sided exact sign (McNemar) test of paired hits: P(X >= better) for X ~ Binomial(better + worse, 1/2),
    the chance of a paired gain at least this large if neither side were better (1.0 when nothing differs)."""
    n = better + worse
    if n == 0:
        return 1.0
    return min(1.0, sum(math.comb(n, i) for i in range(better, n + 1)) / 2 ** n)


def argmax_agreement(reference: np.ndarray, target: np.ndarray, spiking: bool = True) -> ArgmaxAgreement:
    """Agreement of ``target``'s argmax with ``reference``'s over the samples where the reference has a
    single winner (scores (B, classes); spike counts when ``spiking``)."""
    ref, got = np.asarray(reference), np.asarray(target)
    tied, silent = undecided(ref, spiking)
    decided = ~(tied | silent)
    n = int(decided.sum())
    k = int(np.sum(np.argmax(ref, axis=1)[decided] == np.argmax(got, axis=1)[decided]))
    low, high = wilson_interval(k, n) if n else (None, None)
    return ArgmaxAgreement(samples=int(ref.shape[0]), decided=n, agreeing=k, ties=int(tied.sum()),
                           silent=int(silent.sum()), share=k / n if n else None, low=low, high=high)


def random_inputs(samples: int, steps: int, width: int, density: float, seed: int) -> np.ndarray:
    """(samples, steps, width) 0/1 spikes, each entry 1 with probability ``density`` (seeded: numpy's
    default_rng(seed).random(shape) < density). SYNTHETIC: agreement on them is not accuracy."""
    from snncc.errors import SnnccError
    from snncc.limits import check_memory

    if not 0.0 < density <= 1.0:
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    if samples < 1 or steps < 1:
        raise SnnccError("need at least one sample and one step", field="--limit")
    check_memory(samples * steps * width * 9, f"{samples:,} random samples of {steps} steps x {width} channels",
                 field="--limit")
    return (np.random.default_rng(seed).random((samples, steps, width)) < density).astype(np.uint8)


def accuracy(prediction: np.ndarray, labels: np.ndarray) -> dict[str, Any]:
    """Share of correct predictions with its 95 % Wilson interval: value, low, high, correct, samples
    (value None without samples)."""
    pred, lab = np.asarray(prediction).reshape(-1), np.asarray(labels).reshape(-1)
    k, n = int(np.count_nonzero(pred == lab)), int(lab.size)
    low, high = wilson_interval(k, n) if n else (None, None)
    return {"value": k / n if n else None, "low": low, "high": high, "correct": k, "samples": n}


def count_correlation(a: np.ndarray, b: np.ndarray) -> float | None:
    """Pearson correlation of two count arrays (flattened); None when either is constant (undefined;
    equal constant arrays are not evidence of agreement: both may be silent)."""
    a, b = np.asarray(a, np.float64).reshape(-1), np.asarray(b, np.float64).reshape(-1)
    if a.size < 2 or a.std() == 0 or b.std() == 0:
        return None
    return float(np.corrcoef(a, b)[0, 1])
