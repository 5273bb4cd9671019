"""How the model's time maps to the chip's: ``input_pad`` zero steps fed before a sample, the model's output
step t read at the chip's step t + ``output_lag`` (``lowering/timing.py`` solves them; the manifest's ``feed``).

    chip_window(x, input_pad, output_lag)    the chip's input for the model's inputs x (B, T, C)
    read_window(chip_out, output_lag, T)     the model's T steps of output from that run
"""

from __future__ import annotations

import numpy as np


def chip_window(x: np.ndarray, input_pad: int, output_lag: int) -> np.ndarray:
    """The chip's input for IR inputs ``x`` (B, T, C): ``input_pad`` zero steps before, enough after that
    the output can be read for T steps from ``output_lag`` on."""
    b, t, c = x.shape
    tail = max(0, output_lag - input_pad)
    return np.concatenate([np.zeros((b, input_pad, c), x.dtype), x, np.zeros((b, tail, c), x.dtype)], axis=1)


def read_window(chip_out: np.ndarray, output_lag: int, steps: int) -> np.ndarray:
    """The IR's T steps of output from a chip run of ``chip_window``'s input."""
    return chip_out[:, output_lag:output_lag + steps]
