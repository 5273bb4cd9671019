"""snncc/interrupts.py: a Ctrl-C during a guarded step (numba's import) is held back, then delivered as an
ordinary KeyboardInterrupt once the step is over."""

from __future__ import annotations

import os
import signal
import time

import pytest

from snncc.interrupts import sigint_deferred


def test_sigint_is_held_back_during_the_step_and_delivered_after_it():
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finished = False
    with pytest.raises(KeyboardInterrupt):
        with sigint_deferred():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)          # unblocked, the signal would have interrupted this sleep
            finished = True
        time.sleep(1.0)               # delivered on leaving the block: never reached
    assert finished
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler     # the handler is restored


def test_nothing_is_raised_without_a_signal():
    with sigint_deferred():
        value = 1
    assert value == 1 and signal.getsignal(signal.SIGINT) is signal.default_int_handler
