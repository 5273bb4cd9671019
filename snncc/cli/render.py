"""Text renderings of report records (the JSON rendering is ``output.print_json``)."""

from __future__ import annotations

from typing import Any

from typing import TYPE_CHECKING

from rich.table import Table

if TYPE_CHECKING:
    from snncc.ir.graph import Graph

from snncc.cli.output import console, err_console


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list) and len(v) > 4:
        return f"[{len(v)} values]"
    return str(v)


def print_graph_summary(summary: dict[str, Any], title: str | None = None) -> None:
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


def print_import_notes(graph: Graph) -> None:
    """What a frontend assumed (dt inferred, reset chosen, ...): one ``snncc: note:`` line each, on stderr."""
    source = graph.metadata.get("source_file", "")
    for note in graph.metadata.get("import_notes") or []:
        err_console.print(f"snncc: note: {source + ': ' if source else ''}{note}", markup=False, soft_wrap=True)
