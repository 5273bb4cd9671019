"""snncc's emulator of the Xylo v2 SNN core: bit-exact, equal to xylosim 0.1.3 (docs/xylo.md; tests/xylo).

    emulate(spec, inputs, record=False)     the compiled kernel (``kernel.py``, numba), samples over threads; a
                                            small run of a plain spec vectorised in numpy (``vectorized.py``)
    reference_run(spec, inputs, count=...)  the same rules literally in numpy (``literal.py``): the definition
    check_inputs(inputs, n_in)              (T, Nin) or (B, T, Nin) whole event counts, clipped to 15

``numba`` is imported only when ``emulate`` runs (``kernel.py``, under ``kit.compute.sigint_deferred``).
"""

from __future__ import annotations

from snncc.targets.xylo.emulation.literal import (  # noqa: F401  (re-exported: the emulator's public names)
    COUNTERS, check_inputs, decay, reference_run, sat16,
)
from snncc.targets.xylo.emulation.result import STATE_NAMES, XyloResult  # noqa: F401
from snncc.targets.xylo.emulation.weights import effective_weights, wrap16, wrapped_weights  # noqa: F401
from snncc.targets.xylo.spec import XyloSpec


def emulate(spec: XyloSpec, inputs, *, record: bool = False, threads: int | None = None,
            source: str | None = None) -> XyloResult:
    """Run ``inputs`` ((T, Nin) or (B, T, Nin) event counts) through ``spec`` on the compiled kernel, or, for a
    small run of a plain spec while the kernel is not loaded, vectorised in numpy (``vectorized.py``: the same
    results without the kernel's numba import, which costs more than a few samples take).

    ``threads``: threads the samples are spread over (default ``NUMBA_NUM_THREADS``; given: the kernel); each
    sample starts from zero state. Equal, spike for spike and state for state, to ``reference_run``."""
    import sys

    from snncc.targets.xylo.emulation import vectorized

    x = check_inputs(inputs, spec.n_in, source=source)
    small = x.shape[0] * x.shape[1] * spec.n_hidden <= vectorized.SMALL_RUN
    loaded = "snncc.targets.xylo.emulation.kernel" in sys.modules
    if threads is None and small and vectorized.plain(spec) and not loaded:
        return vectorized.run(spec, x, record=record)
    from snncc.targets.xylo.emulation.kernel import prepare, run_prepared

    return run_prepared(prepare(spec), x, record=record, threads=threads)
