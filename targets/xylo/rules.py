"""Xylo design rules: small functions, each refusing in one line that names the rule and the numbers.

``GRAPH_RULES`` run on the IR chain before lowering, ``SPEC_RULES`` on the spec dict after it.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.targets.xylo.chip_table import XyloChip


def _fail(rule: str, field: str) -> None:
    raise SnnccError(rule, field=field)


def check_graph(graph, pops, chip: XyloChip) -> None:
    for rule in GRAPH_RULES:
        rule(graph, pops, chip)


def check_spec(spec: dict, chip: XyloChip) -> None:
    for rule in SPEC_RULES:
        rule(spec, chip)


GRAPH_RULES: list[Callable] = []
SPEC_RULES: list[Callable] = []
