"""The one agreement rule (its single implementation is ``snncc.measure.agreement``; see its docstring).

A sample whose float output has no single winner (a tie at the top, or silence) is left out of the
argmax figure and counted beside it; over the decided samples the share that agree is given with its
95 % Wilson interval; with no decided sample the agreement is undefined (None), never 100 % and never 0.
Every check, fine-tuning record, comparison and bench uses these names.
"""

from __future__ import annotations

from snncc.measure.agreement import (
    DEFAULT_SAMPLES, UNDECIDED_RULE, ArgmaxAgreement, accuracy, argmax_agreement, argmax_hits, chunk_size,
    count_correlation, decided, default_samples, default_samples_note, random_inputs, sign_test, undecided,
    wilson_interval,
)

__all__ = ["DEFAULT_SAMPLES", "UNDECIDED_RULE", "ArgmaxAgreement", "accuracy", "argmax_agreement", "argmax_hits",
           "chunk_size", "count_correlation", "decided", "default_samples", "default_samples_note", "random_inputs",
           "sign_test", "undecided", "wilson_interval"]
