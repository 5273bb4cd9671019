"""How the model's time maps to the chip's: ``input_pad`` zero steps fed before a sample, the model's output
step t read at the chip's step t + ``output_lag`` (``lowering/timing.py`` solves them; the manifest's ``feed``).

    chip_window(x, input_pad, output_lag)    the chip's input for the model's inputs x (B, T, C)
    read_window(chip_out, output_lag, T)     the model's T steps of output from that run
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

Z95 = 1.959963984540054


def clear_winner(counts: np.ndarray) -> np.ndarray:
    """(B,) bool: the row has a unique, non-zero maximum."""
    c = np.asarray(counts)
    top = c.max(axis=1)
    return (top > 0) & ((c == top[:, None]).sum(axis=1) == 1)


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of k successes in n trials."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(0.0, c - h), min(1.0, c + h)


def count_correlation(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, np.float64).ravel(), np.asarray(b, np.float64).ravel()
    if a.std() == 0 or b.std() == 0:
        return 1.0 if np.array_equal(a, b) else 0.0
    return float(np.corrcoef(a, b)[0, 1])


@dataclass
class Agreement:
    agreement: float          # over clear-winner samples
    low: float                # 95 % Wilson interval
    high: float
    counted: int              # clear-winner samples
    ties_or_silent: int       # samples left out
    count_correlation: float

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def line(self) -> str:
        return (f"{self.agreement:.3f} [{self.low:.3f}, {self.high:.3f}] over {self.counted} clear-winner samples "
                f"({self.ties_or_silent} tied or silent left out), count correlation {self.count_correlation:.3f}")


def agreement(deployed_counts: np.ndarray, float_counts: np.ndarray) -> Agreement:
    """Argmax agreement of ``deployed_counts`` with ``float_counts`` (both (B, classes))."""
    mask = clear_winner(float_counts)
    hits = (np.argmax(deployed_counts, axis=1) == np.argmax(float_counts, axis=1))[mask]
    k, n = int(hits.sum()), int(mask.sum())
    lo, hi = wilson(k, n)
    return Agreement(k / n if n else 0.0, lo, hi, n, int(mask.size - n),
                     count_correlation(deployed_counts, float_counts))


def chip_window(x: np.ndarray, input_pad: int, output_lag: int) -> np.ndarray:
    """The chip's input for IR inputs ``x`` (B, T, C): ``input_pad`` zero steps before, enough after that
    the output can be read for T steps from ``output_lag`` on."""
    b, t, c = x.shape
    tail = max(0, output_lag - input_pad)
    return np.concatenate([np.zeros((b, input_pad, c), x.dtype), x, np.zeros((b, tail, c), x.dtype)], axis=1)


def read_window(chip_out: np.ndarray, output_lag: int, steps: int) -> np.ndarray:
    """The IR's T steps of output from a chip run of ``chip_window``'s input."""
    return chip_out[:, output_lag:output_lag + steps]
