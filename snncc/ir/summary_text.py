"""The graph summary (``snncc.ir.summary.graph_summary``) as a rich text table."""

from __future__ import annotations

from typing import Any


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list) and len(v) > 4:
        return f"[{len(v)} values]"
    return str(v)


def render_graph_summary(summary: dict[str, Any], console, title: str | None = None) -> None:
    """Nodes (kind, size, inputs with delays, parameters), totals and the provenance metadata."""
    from rich.table import Table

    table = Table(title=title or f"IR graph '{summary['name']}'  (dt = {summary['dt']} s)", show_lines=False)
    for col in ("node", "kind", "size", "inputs (delay)", "details"):
        table.add_column(col)
    skip = {"name", "kind", "size", "inputs"}
    for row in summary["nodes"]:
        inputs = ", ".join(f"{e['from']} ({e['delay']}{'' if e['port'] == 'spikes' else ', ' + e['port']})" for e in row["inputs"])
        details = ", ".join(f"{k}={_fmt(v)}" for k, v in row.items() if k not in skip)
        table.add_row(row["name"], row["kind"], str(row["size"]), inputs, details)
    console.print(table)
    console.print(f"parameters: {summary['parameters']:,}   LIF neurons: {summary['neurons']:,}")
    meta = summary.get("metadata") or {}
    keep = {k: v for k, v in meta.items() if k in ("model_kind", "update_order", "input_copies", "source_format", "source_file", "source_sha256")}
    if keep:
        console.print("  ".join(f"{k}: {v}" for k, v in keep.items()))
