"""The one time base: how many steps a sample lasts, the same on every target (``snncc.ir.timebase``).

``sample_steps(graph, time_steps)`` -> (steps, the rule that gave them): ``--time-steps`` if given, else
the model's recording length / dt (ceil), else ``DEFAULT_TIME_STEPS`` for every target alike. A target's
calibration, check, fine-tuning and artefact all use it.
"""

from __future__ import annotations

from snncc.ir.timebase import DEFAULT_TIME_STEPS, sample_steps

__all__ = ["DEFAULT_TIME_STEPS", "sample_steps"]
