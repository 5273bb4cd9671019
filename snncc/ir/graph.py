"""The IR graph: typed nodes on a networkx DiGraph, a global ``dt``, a delay on every edge.

An edge ``src -> dst`` carries ``src``'s output at step ``t - delay`` (zero before t = 0).
``port`` selects what a LIF sends: its ``spikes`` (default) or its ``voltage`` (for readouts
of non-spiking integrators). Metadata holds what targets and checks need to know about the
data (input copies, classes, encoding, source hash) as plain JSON-able values.
"""

from __future__ import annotations

import copy
from typing import Any, Iterable, Iterator

import networkx as nx

from snncc.errors import SnnccError
from snncc.ir.nodes import Node

PORTS = ("spikes", "voltage")


class Graph:
    """A network in snncc's IR. Node names are strings; insertion order is kept (deterministic)."""

    def __init__(self, dt: float | None, name: str = "network", metadata: dict[str, Any] | None = None):
        self.dt = None if dt is None else float(dt)
        self.name = name
        self.metadata: dict[str, Any] = dict(metadata or {})
        self.nx = nx.DiGraph()

    # -- building -------------------------------------------------------------------------
    def add(self, name: str, node: Node) -> str:
        if not isinstance(name, str) or not name or "/" in name:
            raise SnnccError("node names are non-empty strings without '/'", field=f"node {name!r}")
        if name in self.nx:
            raise SnnccError("node names must be unique", field=f"node {name!r}")
        self.nx.add_node(name, op=node)
        return name

    def connect(self, src: str, dst: str, delay: int = 0, port: str = "spikes") -> None:
        for end in (src, dst):
            if end not in self.nx:
                raise SnnccError("edge refers to a node that does not exist", field=f"edge {src}->{dst}")
        if port not in PORTS:
            raise SnnccError(f"edge port must be one of {PORTS}", field=f"edge {src}->{dst}")
        self.nx.add_edge(src, dst, delay=int(delay), port=port)

    # -- reading --------------------------------------------------------------------------
    def node(self, name: str) -> Node:
        return self.nx.nodes[name]["op"]

    def __contains__(self, name: str) -> bool:
        return name in self.nx

    def __iter__(self) -> Iterator[str]:
        return iter(self.nx.nodes)

    def items(self) -> Iterator[tuple[str, Node]]:
        for name in self.nx.nodes:
            yield name, self.nx.nodes[name]["op"]

    def of_kind(self, kind: type[Node] | tuple[type[Node], ...]) -> list[str]:
        return [n for n, op in self.items() if isinstance(op, kind)]

    def edges(self) -> list[tuple[str, str, int, str]]:
        return [(u, v, int(d["delay"]), d.get("port", "spikes")) for u, v, d in self.nx.edges(data=True)]

    def delay(self, src: str, dst: str) -> int:
        return int(self.nx.edges[src, dst]["delay"])

    def set_delay(self, src: str, dst: str, delay: int) -> None:
        self.nx.edges[src, dst]["delay"] = int(delay)

    def port(self, src: str, dst: str) -> str:
        return self.nx.edges[src, dst].get("port", "spikes")

    def predecessors(self, name: str) -> list[str]:
        return list(self.nx.predecessors(name))

    def successors(self, name: str) -> list[str]:
        return list(self.nx.successors(name))

    def copy(self, replaced: Iterable[Any] = ()) -> "Graph":
        """A deep copy: passes return new graphs and never mutate their input. ``replaced``: arrays of this graph
        the caller assigns anew in the copy before anything reads them (a pass rewriting every weight): they are
        not copied, the copy holds them until then."""
        return copy.deepcopy(self, {id(a): a for a in replaced})

    def __repr__(self) -> str:
        return f"Graph({self.name!r}, dt={self.dt}, nodes={list(self.nx.nodes)})"
