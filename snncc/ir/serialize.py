"""IR graphs to and from a ``.snnir`` file: a zip of ``graph.json`` plus one ``.npy`` per array.

Deterministic (fixed zip timestamps, sorted entries), loaded with ``allow_pickle=False``.
"""

from __future__ import annotations

import io
import json
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from snncc.atomic import atomic_path
from snncc.errors import SnnccError
from snncc.limits import check_memory, check_real, whole_number
from snncc.ir.graph import Graph
from snncc.ir.nodes import NODE_TYPES

FORMAT = "snncc-ir"
VERSION = 1
_EPOCH = (1980, 1, 1, 0, 0, 0)


def graph_to_record(g: Graph) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """A JSON-able description of ``g`` and the arrays it refers to by key."""
    arrays: dict[str, np.ndarray] = {}
    nodes = []
    for name, op in g.items():
        fields: dict[str, Any] = {}
        omit = getattr(op, "OMIT_AT_DEFAULT", {})
        for key, value in op.scalars().items():
            if key in omit and value == omit[key]:
                continue        # a newer field at its default: the file reads as it did before the field existed
            fields[key] = value
        for key, arr in op.arrays().items():
            ref = f"{name}/{key}"
            arrays[ref] = arr
            fields[key] = {"array": ref}
        nodes.append({"name": name, "kind": op.kind, "fields": fields})
    edges = [{"src": u, "dst": v, "delay": d, "port": p} for u, v, d, p in g.edges()]
    record = {
        "format": FORMAT,
        "version": VERSION,
        "name": g.name,
        "dt": g.dt,
        "metadata": g.metadata,
        "nodes": nodes,
        "edges": edges,
    }
    return record, arrays


FINGERPRINT_IGNORES = ("source_file",)     # where the file lay, not what it holds


def graph_fingerprint(g: Graph) -> str:
    """SHA-256 of what ``g`` computes and states: its record (dt, nodes with every field, edges with delays and
    ports, metadata except ``FINGERPRINT_IGNORES``) as canonical JSON, then each array's dtype, shape and bytes
    in key order. Two loads of one model file with the same options (dt, reset, ...) give the same fingerprint;
    any other dt, reset, weight or delay gives another."""
    import hashlib

    record, arrays = graph_to_record(g)
    record = dict(record, metadata={k: v for k, v in (record.get("metadata") or {}).items()
                                    if k not in FINGERPRINT_IGNORES})
    h = hashlib.sha256(json.dumps(record, sort_keys=True, default=str).encode("utf-8"))
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"\n{key} {a.dtype.str} {a.shape}\n".encode("utf-8"))
        h.update(a.tobytes() if a.dtype.hasobject else a.reshape(-1).view(np.uint8))   # tobytes()'s bytes, uncopied
    return h.hexdigest()


def graph_from_record(record: dict[str, Any], arrays: dict[str, np.ndarray]) -> Graph:
    if record.get("format") != FORMAT:
        raise SnnccError(f"not an snncc IR file (format tag {record.get('format')!r})", field="format")
    if record.get("version") != VERSION:
        raise SnnccError(f"unsupported IR version {record.get('version')!r} (this snncc reads {VERSION})", field="version")
    g = Graph(record.get("dt"), name=record.get("name", "network"), metadata=record.get("metadata") or {})
    for entry in record["nodes"]:
        cls = NODE_TYPES.get(entry.get("kind"))
        if cls is None:
            raise SnnccError(f"unknown node kind {entry.get('kind')!r}", field=f"node {entry.get('name')!r}")
        kwargs = {}
        for key, value in entry["fields"].items():
            if isinstance(value, dict) and "array" in value:
                if value["array"] not in arrays:
                    raise SnnccError("array missing from file", field=value["array"])
                value = arrays[value["array"]]
            kwargs[key] = value
        for key in ("n", "width"):
            if key in kwargs:
                count = whole_number(kwargs[key], field=f"node {entry.get('name')!r}.{key}")
                check_memory(8 * count, f"a node of {count:,} units", field=f"node {entry.get('name')!r}.{key}")
        if "max_spikes" in kwargs:
            kwargs["max_spikes"] = whole_number(kwargs["max_spikes"], field=f"node {entry.get('name')!r}.max_spikes")
        for key, value in kwargs.items():
            if isinstance(value, np.ndarray):
                check_real(value, field=f"node {entry.get('name')!r}.{key}")
        try:
            op = cls(**kwargs)
        except (TypeError, ValueError) as ex:
            raise SnnccError(f"fields do not match a {cls.kind} node ({ex})", field=f"node {entry.get('name')!r}") from None
        g.add(entry["name"], op)
    for e in record["edges"]:
        g.connect(e["src"], e["dst"], delay=e["delay"], port=e.get("port", "spikes"))
    return g


def save_graph(g: Graph, path: str | Path) -> None:
    """Write ``g`` atomically and byte-identically for identical graphs."""
    record, arrays = graph_to_record(g)
    with atomic_path(path) as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            info = zipfile.ZipInfo("graph.json", date_time=_EPOCH)
            info.compress_type = zipfile.ZIP_DEFLATED
            zf.writestr(info, json.dumps(record, indent=1, sort_keys=True))
            for key in sorted(arrays):
                buf = io.BytesIO()
                np.save(buf, np.ascontiguousarray(arrays[key]), allow_pickle=False)
                info = zipfile.ZipInfo(f"arrays/{key}.npy", date_time=_EPOCH)
                info.compress_type = zipfile.ZIP_DEFLATED
                zf.writestr(info, buf.getvalue())


def load_graph(path: str | Path) -> Graph:
    path = Path(path)
    try:
        with zipfile.ZipFile(path) as zf:
            for info in zf.infolist():
                check_memory(info.file_size, f"the archive member {info.filename} (unpacked)", field=info.filename)
            check_memory(sum(i.file_size for i in zf.infolist()), "the archive's members together (unpacked)",
                         field="graph.json")
            record = json.loads(zf.read("graph.json"))
            arrays = {}
            for item in zf.namelist():
                if item.startswith("arrays/") and item.endswith(".npy"):
                    arrays[item[len("arrays/"):-len(".npy")]] = np.load(io.BytesIO(zf.read(item)), allow_pickle=False)
        return graph_from_record(record, arrays)
    except SnnccError as err:
        raise err.with_file(str(path)) from None
    # damaged deflate data (zlib.error), a truncated member (EOFError), an unknown compression
    # (NotImplementedError) or an encrypted member (RuntimeError): one line like every other damage
    except (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError, RuntimeError, KeyError, ValueError,
            json.JSONDecodeError, OSError) as ex:
        raise SnnccError(f"not a readable snncc IR file ({type(ex).__name__})", file=str(path), field="graph.json") from None
