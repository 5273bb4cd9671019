"""A chip that runs only one reset rule: each population with the other rule is refused, or, when the
user allows it, given the chip's rule on a copy of the graph (``snncc check`` then measures the cost).

    reset(p) == from_  and not allow  ->  SnnccError(refusal) on node '<p>'.reset
    reset(p) == from_  and allow      ->  reset(p) := to, noted as '<p>: reset <from_> -> <to> (<why>)'
"""

from __future__ import annotations

from collections.abc import Iterable

from snncc.errors import SnnccError
from snncc.ir.graph import Graph


def change_reset(graph: Graph, lifs: Iterable[str], *, from_: str, to: str, allow: bool, refusal: str,
                 why: str) -> tuple[Graph, list[str]]:
    """``graph`` (a copy when a reset changes) and the notes of the changes; ``refusal`` is the one-line
    rule when ``allow`` is false."""
    g, changes = graph, []
    for lif in lifs:
        if graph.node(lif).reset != from_:
            continue
        if not allow:
            raise SnnccError(refusal, field=f"node '{lif}'.reset")
        if g is graph:
            g = graph.copy()
        g.node(lif).reset = to
        changes.append(f"{lif}: reset {from_} -> {to} ({why})")
    return g, changes
