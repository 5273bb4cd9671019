"""Argmax agreement between two count arrays, with a 95 % Wilson interval and the clear-winner rule.

    clear winner   a sample whose REFERENCE counts have one strict maximum (no tie at the top, not silent)
    agreement      share of clear-winner samples whose other argmax equals the reference's
    interval       Wilson score interval at z = 1.96 over those samples:
                   (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)
Samples without a clear winner are left out of the figure and counted beside it (tied, silent).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

Z95 = 1.959963984540054


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of ``successes`` out of ``n`` (``(nan, nan)`` when n is 0)."""
    if n <= 0:
        return math.nan, math.nan
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == n else min(1.0, centre + half)
    return low, high


def clear_winners(counts: np.ndarray) -> np.ndarray:
    """(N,) bool: the sample's counts have one strict maximum (neither tied at the top nor all zero)."""
    c = np.asarray(counts)
    if c.shape[1] < 2:
        return c[:, 0] > 0
    top2 = np.sort(c, axis=1)[:, -2:]
    return top2[:, 1] > top2[:, 0]


@dataclass
class Agreement:
    """Argmax agreement over the clear-winner samples, with its interval and what was left out."""

    value: float             # nan when no sample has a clear winner (undefined, never 100 %)
    low: float
    high: float
    agree: int
    clear: int
    samples: int
    tied: int                # reference tied at the top (not all zero)
    silent: int              # reference silent (all counts zero)

    def as_dict(self) -> dict:
        return asdict(self)

    def text(self) -> str:
        if not self.clear:
            return f"undefined (no sample of {self.samples} has a clear winner)"
        return (f"{self.value:.3f} [{self.low:.3f}, {self.high:.3f}] over {self.clear} of {self.samples} samples "
                f"({self.tied} tied, {self.silent} silent left out)")


def argmax_agreement(reference: np.ndarray, other: np.ndarray) -> Agreement:
    """How often ``other``'s argmax equals ``reference``'s on samples where the reference has a clear winner."""
    ref, oth = np.asarray(reference), np.asarray(other)
    clear = clear_winners(ref)
    silent = int(np.count_nonzero(ref.max(axis=1) == 0))
    n = int(clear.sum())
    agree = int(np.count_nonzero((np.argmax(ref, axis=1) == np.argmax(oth, axis=1)) & clear))
    low, high = wilson(agree, n)
    return Agreement(agree / n if n else math.nan, low, high, agree, n, int(ref.shape[0]),
                     int(ref.shape[0]) - n - silent, silent)


def argmax_hits(reference: np.ndarray, other: np.ndarray) -> np.ndarray:
    """(clear,) bool: per clear-winner sample of ``reference``, whether ``other``'s argmax equals it."""
    ref, oth = np.asarray(reference), np.asarray(other)
    clear = clear_winners(ref)
    return (np.argmax(ref, axis=1) == np.argmax(oth, axis=1))[clear]


def sign_test(better: int, worse: int) -> float:
    """One-sided exact sign (McNemar) test: P(X >= better) for X ~ Binomial(better + worse, 1/2), the chance of a
    paired gain at least this large if neither side were better (1.0 when nothing differs)."""
    n = better + worse
    if n == 0:
        return 1.0
    return min(1.0, sum(math.comb(n, i) for i in range(better, n + 1)) / 2 ** n)

