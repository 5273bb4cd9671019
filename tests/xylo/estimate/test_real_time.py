"""The real-time ESTIMATE: core cycles per step from per-operation costs, against dt."""

import numpy as np
import pytest

from snncc.targets.xylo.estimate import real_time as rules
from tests.xylo.lowering.test_design_rules import small_spec


def test_cycles_grow_with_the_network_and_real_time_is_judged_against_dt():
    small, big = small_spec(n=10), small_spec(n=400, n_in=16, n_out=8)
    assert rules.cycles_per_step(small) < rules.cycles_per_step(big)
    # quiet networks need fewer cycles than the worst case
    assert rules.cycles_per_step(big, 0.05, 0.02, 0.01) < rules.cycles_per_step(big)
    # hand count for the small spec (every operation once per step): inputs 4 * (10 * 3.5 + 1), recurrent
    # 10 * (fan-out * 7 + 3), to the outputs 10 * (1 + 3 * 8), neurons 10 * (19 + 3) + 3 * 12
    fan = np.mean(np.count_nonzero(small["weights_rec"].any(axis=2), axis=1))
    assert rules.cycles_per_step(small) == pytest.approx(4 * 36 + 10 * (fan * 7 + 3) + 10 * 25 + 10 * 22 + 36)
    fast = rules.real_time(small, dt=1e-3)
    assert fast.real_time and "runs in real time" in fast.line()
    slow = rules.real_time(big, dt=1e-5)
    assert not slow.real_time and "does NOT run in real time" in slow.line() and slow.as_dict()["margin"] < 1
