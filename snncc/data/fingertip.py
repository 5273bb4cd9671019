"""The recording's geometry, shared by both generator versions: the iCub fingertip's taxel centres,
the slide (15.5 mm at 20 mm/s) and where a letter's dots lie at the slide's start."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from snncc.data.letters import DOTS, dot_cell


class CellGeometry(Protocol):
    """The Braille cell's placement in the finger frame (mm): both generators' parameters have it."""

    x_first_row: float
    row_pitch: float
    z_centre: float
    col_pitch: float


# Taxel centres of the iCub fingertip (mm): x along the finger (tip towards -x), y pad normal, z.
TAXELS = np.array(
    [
        [-10.3, 2.2, -3.8], [-10.3, 4.4, 0.0], [-10.3, 2.2, 3.8], [-12.5, -1.4, 4.4],
        [-12.5, -1.4, -4.4], [-14.1, 2.2, 3.8], [-14.1, 4.4, 0.0], [-14.1, 2.2, -3.8],
        [-18.7, 1.6, -2.5], [-18.7, 3.15, 0.0], [-18.7, 1.6, 2.5], [-20.9, 0.0, 0.0],
    ],
    dtype=np.float64,
)

SLIDE_MM = 15.5
SPEED_MM_S = 20.0


def dot_positions(letter: str, p: CellGeometry) -> np.ndarray:
    """(n_dots, 2) positions (x, z) in mm of a letter's dots at slide start, no jitter."""
    out = []
    for d in DOTS[letter]:
        row, col = dot_cell(d)
        out.append((p.x_first_row + row * p.row_pitch, p.z_centre + (col - 0.5) * p.col_pitch))
    return np.array(out, dtype=np.float64).reshape(-1, 2)
