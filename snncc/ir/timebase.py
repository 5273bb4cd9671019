"""How many time steps a recording of a given length takes: the one rule every target uses."""

from __future__ import annotations

import math


def recording_steps(length_s: float, dt: float) -> int:
    """``ceil(length / dt)``; the small epsilon keeps 1.35 / 0.005 = 270.00000000000006 from becoming 271."""
    return int(math.ceil(float(length_s) / float(dt) - 1e-9))
