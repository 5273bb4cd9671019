"""What a search trial's model costs on a target: the shared half of the ``hardware`` capability.

A target's costs are a ``SearchCosts``: its figures' record states ``objectives`` (what a search may
optimise), ``columns`` (what a search report shows per trial, in order), ``front`` (the objectives the
Pareto front weighs beside accuracy), ``published`` (a published measurement shown beside the trials,
empty where none exists) and ``label`` (what the figures are: ESTIMATE wording), as class attributes;
the target writes only ``figures(graph, inputs, labels, options, ...)``.

    tiled_inputs(x, graph, width)        inputs in the model's channels, tiled to an artefact's input copies
    timed()                              wall seconds of the block, for the trial's record
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator, Mapping
from typing import Any, ClassVar

import numpy as np

from snncc.targets.base import Figure, Objective


class SearchCosts:
    """The ``hardware`` capability's answer (``base.HardwareCosts``): class attributes, ``figures`` per trial."""

    objectives: ClassVar[Mapping[str, Objective]] = {}
    columns: ClassVar[Mapping[str, Figure]] = {}
    front: ClassVar[tuple[str, ...]] = ()
    label: ClassVar[str] = ""

    def __init__(self, target: Any, published: Mapping[str, float | str] | None = None) -> None:
        self.target = target
        self.published: Mapping[str, float | str] = dict(published or {})


def tiled_inputs(x: np.ndarray, graph: Any, width: int) -> np.ndarray:
    """``x`` (B, T, C) as the artefact takes it: the model's ``input_copies`` tiled on the channel axis when
    ``C x copies`` is the artefact's input ``width``."""
    x = np.asarray(x)
    k = int(graph.metadata.get("input_copies", 1) or 1)
    if k > 1 and x.shape[2] * k == width:
        return np.tile(x, (1, 1, k))
    return x


class _Clock:
    seconds = 0.0


@contextlib.contextmanager
def timed() -> Iterator[_Clock]:
    """``with timed() as clock: ...`` then ``clock.seconds``: the block's wall time."""
    clock = _Clock()
    started = time.perf_counter()
    try:
        yield clock
    finally:
        clock.seconds = time.perf_counter() - started


__all__ = ["SearchCosts", "tiled_inputs", "timed"]
