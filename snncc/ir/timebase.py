"""How many time steps a sample takes: the one rule every target uses.

    --time-steps T                          if given;
    ceil(recording_length_s / dt)           if the model states its recording length (graph metadata);
    DEFAULT_TIME_STEPS (256)                otherwise, and the compile report says so in one line.

A Loihi bundle's tSample, a Jetson artefact's unrolled T, a Xylo artefact's calibration samples, the C
target's, and the inputs every check, comparison and fine-tuning runs on all follow it, so a model that
states no recording length is treated alike by every target. 256 is the sample length of the one task
the published NIR graphs carry (the NIR paper's Braille data: 256 steps of 0.1 ms per letter); until
this round Loihi and Jetson used 100 and Xylo 256, so one graph ran different experiments per target.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

DEFAULT_TIME_STEPS = 256
NO_LENGTH_RULE = (f"{DEFAULT_TIME_STEPS} steps, snncc's default for a model that states no recording length "
                  "(pass --time-steps to set it)")


def recording_steps(length_s: float, dt: float) -> int:
    """``ceil(length / dt)``; the small epsilon keeps 1.35 / 0.005 = 270.00000000000006 from becoming 271."""
    return int(math.ceil(float(length_s) / float(dt) - 1e-9))


def sample_steps(graph: Graph, time_steps: int | float | None = None) -> tuple[int, str]:
    """(time steps per sample, the rule that gave them) by the module's rule; a bad count is one line."""
    from snncc.errors import SnnccError

    if time_steps is not None:
        if isinstance(time_steps, bool) or int(time_steps) != time_steps or time_steps < 1:
            raise SnnccError(f"time steps must be a whole number >= 1, got {time_steps}", field="--time-steps")
        return int(time_steps), "--time-steps"
    length = graph.metadata.get("recording_length_s")
    if length is None:
        return DEFAULT_TIME_STEPS, NO_LENGTH_RULE
    steps = recording_steps(length, graph.dt)
    if steps < 1:
        raise SnnccError(f"recording_length_s / dt gives {steps} time steps; pass --time-steps", field="--time-steps")
    return steps, f"ceil({length} s / {graph.dt} s)"
