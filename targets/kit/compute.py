"""Computing within the machine's means: one compute thread for small work, rounding with error feedback,
Ctrl-C held back while numba imports, memory and time-step bounds checked before anything is allocated.

    one_thread()                        torch and every native thread pool on one thread within the block
    round_with_feedback(h, c, step)     integers for real coefficients, each rounding error fed to the rest
    damped(h, damping)                  a Hessian with a ridge, for the rounding above
    sigint_deferred()                   Ctrl-C during the block is raised after it (numba's C init)
    check_memory(n_bytes, what)         refuse an allocation above the memory cap, in one line
    check_time_steps(steps, what)       refuse a sample longer than MAX_TIME_STEPS
    whole_number(value)                 a count from a file, checked
    integer_units(w)                    w = m * g (m integers, g a power of two) where float32 sums m exactly
    UnitsProduct(m_t, bound)            x @ m_t exactly for small integer x (spikes: C where large, else BLAS)
    spike_products                      spikes times a large matrix over the nonzero inputs only (C kernels)
    transposed(a, factor)               (a * factor).T in C order, copied in blocks of rows (cache-friendly)
"""

from __future__ import annotations

from snncc import spike_products
from snncc.exact_products import FLOAT32_EXACT, UnitsProduct, integer_units
from snncc.interrupts import sigint_deferred
from snncc.limits import MAX_STREAM_STEPS, MAX_TIME_STEPS, check_memory, check_time_steps, human_bytes, whole_number
from snncc.rounding import damped, round_with_feedback
from snncc.threads import one_thread
from snncc.transpose import transposed

__all__ = ["one_thread", "round_with_feedback", "damped", "sigint_deferred", "check_memory", "check_time_steps",
           "whole_number", "human_bytes", "MAX_TIME_STEPS", "MAX_STREAM_STEPS", "integer_units",
           "UnitsProduct", "spike_products", "FLOAT32_EXACT", "transposed"]
