"""Older NIR files that today's ``nir.read`` rejects, read where their meaning is unambiguous.

NIR 0.2-era writers (the NIR paper's 2023 Braille sub-graph, for one) stored a sub-graph's
``Input`` with the shape of the OUTER graph's input instead of the shape of the node it feeds,
so today's type inference refuses the file even with ``type_check=False`` (sub-graphs are
type-checked when they are built). Rule applied here, to the raw HDF5 record before any node is
built: an ``Input`` whose every successor expects one and the same size n (an Affine/Linear's
weight columns, a neuron population's size, a sub-graph's own Input) but which declares another
size is read with shape n, and a note says so. If its successors disagree, or a size cannot be
told from their parameters, the file is refused with one line. Edges naming a sub-graph instead of
its Input/Output node are left as they are: the NIR frontend resolves them (a sub-graph with one
Input and one Output).

What such a file cannot hold is refused, not guessed: NIR's writer stored a CubaLIF's ``w_in`` only
from 19 October 2023 on (NIR commit 658d18d; release 0.2 did not, 1.0 does), so an older file's CubaLIF
record without ``w_in`` has lost
its input weight, and with it the gain from input to voltage (``(w_in dt/tau_syn)(r dt/tau_mem)``
under NIR's equations); a CubaLIF record without ``w_in`` is refused in one line naming the node
(``LegacyFileLacks``). The NIR paper's 2023 Braille sub-graph is such a file: docs/nir.md says what
else it lacks.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from snncc.errors import SnnccError

NEURONS = ("LIF", "CubaLIF", "LI", "CubaLI", "IF", "I", "Threshold", "Scale", "Delay")
LOST_FIELDS = {"CubaLIF": "w_in"}   # node type -> the field NIR's writer up to release 0.2 did not store


class LegacyFileLacks(SnnccError):
    """An older NIR file that was read but lacks what its meaning needs: refused as it is, never retried."""


def _text(value: Any) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


def _input_size(node: dict) -> int | None:
    """How many values ``node`` (a raw NIR record) takes in, from its own parameters, or None."""
    kind = _text(node.get("type", ""))
    if kind in ("Affine", "Linear") and "weight" in node:
        return int(np.shape(node["weight"])[-1])
    if kind in NEURONS:
        for key in ("tau_mem", "tau", "r", "v_threshold", "threshold", "scale", "delay"):
            if key in node:
                return int(np.size(node[key]))
    if kind == "NIRGraph":
        ins = [n for n in node["nodes"].values() if _text(n.get("type", "")) == "Input"]
        if len(ins) == 1:
            fed = _fed_sizes(node, next(k for k, n in node["nodes"].items() if n is ins[0]))
            return fed.pop() if len(fed) == 1 else int(np.prod(ins[0]["shape"]))
    return None


def _fed_sizes(graph: dict, name: str) -> set[int | None]:
    edges = [(_text(a), _text(b)) for a, b in graph["edges"]]
    return {_input_size(graph["nodes"][b]) if b in graph["nodes"] else None for a, b in edges if a == name}


def normalise(graph: dict, path: str, notes: list[str], source: str) -> None:
    """Fix, in place, the Input shapes of ``graph`` and its sub-graphs that disagree with what they feed."""
    where_graph = f"node/{path.replace('.', '/')}" if path else "node/"
    for key in ("nodes", "edges"):
        if not isinstance(graph.get(key), dict if key == "nodes" else (list, tuple, np.ndarray)):
            raise SnnccError(f"missing or not a {'group of nodes' if key == 'nodes' else 'list of edges'} (every NIR "
                             "graph and sub-graph has both)", file=source, field=where_graph + key)
    if any(np.shape(e) != (2,) for e in graph["edges"]):
        raise SnnccError("every edge must be a pair (source, target)", file=source, field=where_graph + "edges")
    graph["edges"] = [(_text(a), _text(b)) for a, b in graph["edges"]]
    for name, node in graph["nodes"].items():
        where = f"{path}{name}"
        if _text(node.get("type", "")) == "NIRGraph":
            normalise(node, where + ".", notes, source)
            node["type_check"] = False
    if not path:
        return
    for name, node in graph["nodes"].items():
        if _text(node.get("type", "")) != "Input":
            continue
        sizes = _fed_sizes(graph, name)
        declared = int(np.prod(node["shape"]))
        if None in sizes or len(sizes) != 1:
            if declared not in sizes:
                raise SnnccError(f"older NIR file: sub-graph input '{path}{name}' declares {declared} values and feeds "
                                 f"nodes of sizes {sorted(s for s in sizes if s is not None)} (undecidable)",
                                 file=source, field=f"node '{path}{name}'")
            continue
        (size,) = sizes
        if size != declared:
            node["shape"] = np.array([size])
            notes.append(f"older NIR file: sub-graph input '{path}{name}' declared shape [{declared}] but feeds "
                         f"{size} values; read as [{size}] (the size of what it feeds)")


def refuse_lost_fields(graph: dict, path: str, source: str) -> None:
    """Refuse ``graph`` (a raw NIR record) if a node lacks a field the older writers did not store."""
    for name, node in graph["nodes"].items():
        kind = _text(node.get("type", ""))
        if kind == "NIRGraph":
            refuse_lost_fields(node, f"{path}{name}.", source)
            continue
        lost = LOST_FIELDS.get(kind)
        if lost is None or lost in node:
            continue
        r = np.asarray(node.get("r", np.nan), np.float64)
        unit_r = bool(r.size) and bool(np.all(r == 1.0))
        raise LegacyFileLacks(
            f"older NIR file: this {kind} stores no {lost} (NIR's writer up to release 0.2 did not write it)"
            + (" and has r = 1" if unit_r else "") + ", so the gain from its input to its voltage is not in the "
            "file; re-export the model with a current NIR writer", file=source, field=f"node '{path}{name}'.{lost}")


def read_legacy(path: str | Path) -> tuple[Any, list[str]]:
    """(nir.NIRGraph, notes) for an older NIR file, or a one-line SnnccError."""
    import h5py
    import nir
    from nir.serialization import hdf2dict

    try:
        with h5py.File(str(path), "r") as f:
            raw = hdf2dict(f["node"])
    except Exception as ex:  # not HDF5 / no 'node' group
        raise SnnccError(f"not a readable NIR graph ({type(ex).__name__})", file=str(path), field="format") from None
    if _text(raw.get("type", "")) != "NIRGraph" or "nodes" not in raw:
        raise SnnccError("not a NIR graph (no top-level NIRGraph)", file=str(path), field="format")
    notes: list[str] = []
    normalise(raw, "", notes, str(path))
    refuse_lost_fields(raw, "", str(path))
    raw["type_check"] = False
    try:
        return nir.dict2NIRNode(raw), notes
    except Exception as ex:  # the nir builders raise assorted types
        detail = str(ex).strip().splitlines()[0] if str(ex).strip() else type(ex).__name__
        raise SnnccError(f"not a readable NIR graph, even as an older NIR file ({detail})", file=str(path),
                         field="format") from None
