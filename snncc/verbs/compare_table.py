"""``snncc compare``'s record as text (rich tables), Markdown and a figure: four tables from the same rows.

    agreement    each row's argmax agreement with the float graph, its 95 % interval, decided / tied / silent
                 samples, accuracy where labels exist, the artefact's SHA-256 (or why the target cannot take it)
    loss         the loss by cause in the same columns for every target ("—" where a cause cannot occur there)
    hardware     resources against the chip's limits, the real-time verdict, energy and delay (ESTIMATE, with source)
    NeuroBench   footprint, connection and activation sparsity, synaptic operations per sample (NeuroBench 2.3)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from snncc.targets.kit.checks import CANNOT, CAUSE_TITLES, CAUSES

if TYPE_CHECKING:
    from rich.console import Console

    from matplotlib.axes import Axes

    from snncc.targets.kit.profile import Resource
    from snncc.verbs.compare import Comparison, Row


def _agreement(row: Row) -> str:
    if row.error is not None:
        return "cannot: " + row.error.removeprefix("snncc: error: ")
    a = row.argmax
    if row.argmax_agreement is None or a is None or a.low is None or a.high is None:
        return "undefined" + (" (outputs silent)" if a is not None and a.silent == a.samples else "")
    if row.kind == "float":
        return "1 (the reference)"
    return f"{row.argmax_agreement:.3f} [{a.low:.3f}, {a.high:.3f}]"


def _counts(row: Row) -> str:
    a = row.argmax
    return "" if a is None else f"{a.decided} / {a.ties} / {a.silent}"


def _cause(row: Row, cause: str) -> str:
    if row.kind != "artefact" or row.error is not None:
        return ""
    if cause not in row.possible:
        return CANNOT
    value = row.causes.get(cause)
    return "undefined" if value is None else f"{value:+.1f}"


def _resources(row: Row) -> str:
    return "; ".join(r.text() for r in row.resources)


def _real_time(row: Row) -> str:
    rt = row.real_time
    if rt is None:
        return ""
    worst = "" if rt.worst_margin is None else f", worst {rt.worst_margin:.2f}x"
    return f"{'yes' if rt.real_time else 'NO'} ({rt.margin:.2f}x{worst}; {rt.basis.split(':')[0]})"


def _energy(row: Row) -> str:
    return "" if row.energy is None else row.energy.text()


def _neurobench(row: Row) -> list[str]:
    nb = row.neurobench
    if nb is None:
        return ["", "", "", "", "", ""]
    ops = nb.synaptic_operations
    return [f"{nb.footprint:,}", f"{nb.connection_sparsity:.3f}", f"{nb.activation_sparsity:.4f}",
            f"{ops['Effective_ACs']:,.0f}", f"{ops['Effective_MACs']:,.0f}", f"{ops['Dense']:,.0f}"]


def tables(result: Comparison) -> list[tuple[str, list[str], list[list[str]]]]:
    """(title, header, rows) of the four tables."""
    labelled = result.labelled
    head = ["target", "agreement with the float graph [95 %]", "decided / tied / silent"]
    head += ["accuracy"] if labelled else []
    head += ["SHA-256"]
    first = []
    for r in result.rows:
        cells = [r.target, _agreement(r), _counts(r)]
        cells += ["" if r.accuracy is None else f"{100 * r.accuracy:.1f} %"] if labelled else []
        cells += [(r.sha256 or "")[:16] + ("..." if r.sha256 else "")]
        first.append(cells)
    losses = [[r.target, *[_cause(r, c) for c in CAUSES], "" if r.total_points is None else f"{r.total_points:+.1f}"]
              for r in result.rows if r.kind == "artefact"]
    hardware = [[r.target, _resources(r), _real_time(r), _energy(r)] for r in result.rows
                if r.kind == "artefact" and r.error is None]
    bench = [[r.target, *_neurobench(r)] for r in result.rows if r.neurobench is not None]
    return [("agreement with the float graph on the same inputs", head, first),
            ("loss by cause (agreement points lost against the stage before; successive, not independent)",
             ["target", *[CAUSE_TITLES[c] for c in CAUSES], "total"], losses),
            ("hardware (energy and delay only where a published cost model exists: ESTIMATES)",
             ["target", "resources (used / limit)", "real time at the measured event rates", "energy, delay per sample"],
             hardware),
            ("NeuroBench 2.3 (per sample; footprint as deployed)",
             ["target", "footprint B", "connection sparsity", "activation sparsity", "Effective_ACs", "Effective_MACs",
              "Dense"], bench)]


def header_lines(result: Comparison) -> list[str]:
    return [f"{result.model} on {result.inputs}",
            f"time base: {result.steps} steps per sample ({result.steps_rule}), the same for every row"]


def render_text(result: Comparison, console: Console) -> None:
    from rich.table import Table

    for line in header_lines(result):
        console.print(line, markup=False, soft_wrap=True)
    for title, head, rows in tables(result):
        if not rows:
            continue
        table = Table(title=title, title_justify="left", show_lines=False)
        for name in head:
            table.add_column(name, overflow="fold")
        for cells in rows:
            table.add_row(*cells)
        console.print(table)
    for r in result.rows:
        if r.command:
            console.print(f"{r.target}: rebuilt by `{r.command}`", markup=False, soft_wrap=True)
    for note in result.notes:
        console.print(f"note: {note}", markup=False, soft_wrap=True)
    if result.markdown:
        console.print(f"wrote {result.markdown}", markup=False)
    if result.figure:
        console.print(f"wrote {result.figure}", markup=False)


def markdown(result: Comparison) -> str:
    """The four tables as GitHub Markdown, with the header lines and the commands."""
    out = [f"# snncc compare: {Path(result.model).name}", ""] + [f"{line}  " for line in header_lines(result)] + [""]
    for title, head, rows in tables(result):
        if not rows:
            continue
        out += [f"## {title}", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        out += ["| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |" for cells in rows]
        out.append("")
    commands = [f"- {r.target}: `{r.command}`" for r in result.rows if r.command]
    if commands:
        out += ["## rebuilding each artefact", ""] + commands + [""]
    if result.notes:
        out += ["## notes", ""] + [f"- {n}" for n in result.notes] + [""]
    return "\n".join(out)


def draw(result: Comparison, path: Path) -> None:
    """Three panels: agreement with intervals per row (the ceiling in grey); per target, its most used limited
    resource as a share of the chip's limit; energy per sample where one is estimated (log scale, values written)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from snncc.atomic import atomic_path

    shown = [r for r in result.rows if r.argmax_agreement is not None and r.kind != "float"]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), gridspec_kw={"width_ratios": [3, 2, 2]})
    ax = axes[0]
    for i, r in enumerate(shown):
        share = float(r.argmax_agreement or 0.0)
        low = share if r.argmax is None or r.argmax.low is None else r.argmax.low
        high = share if r.argmax is None or r.argmax.high is None else r.argmax.high
        colour = "0.6" if r.kind == "ceiling" else "C0"
        ax.errorbar([i], [share], yerr=[[share - low], [high - share]], fmt="o", color=colour, capsize=4)
    ax.set_xticks(range(len(shown)), [r.target.replace(", ", "\n") for r in shown], rotation=0)
    ax.set_ylabel("agreement with the float graph (95 %)")
    ax.set_ylim(0, 1.02)
    ax.set_title(f"{Path(result.model).name}: {result.samples} samples x {result.steps} steps", fontsize=10)
    ax.grid(axis="y", alpha=0.3)
    _draw_resources(axes[1], result)
    _draw_energy(axes[2], result)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=120)
    plt.close(fig)


def most_used(row: Row) -> Resource | None:
    """The row's resource with the largest share of its chip's limit (None where no resource states a limit)."""
    limited = [r for r in row.resources if r.limit]
    return max(limited, key=lambda r: r.used / float(r.limit or 1), default=None)


def _draw_resources(ax: Axes, result: Comparison) -> None:
    bars = [(r.target, used) for r in result.rows if r.kind == "artefact" and (used := most_used(r)) is not None]
    if not bars:
        ax.axis("off")
        ax.text(0.5, 0.5, "no target states a limit\nfor what this network uses", ha="center", va="center")
        return
    shares = [100.0 * res.used / float(res.limit or 1) for _, res in bars]
    ax.bar([t for t, _ in bars], shares, color=["C3" if v > 100 else "C2" for v in shares])
    for i, ((_, res), v) in enumerate(zip(bars, shares)):
        ax.text(i, v, f"{res.what.split(' (')[0]}\n{v:.0f} %", ha="center", va="bottom", fontsize=7)
    ax.axhline(100, color="0.4", lw=0.8, ls="--")
    ax.set_ylim(0, max(110.0, max(shares) * 1.25))
    ax.set_ylabel("most used resource, % of the chip's limit")
    ax.set_title("resources against each chip's limits", fontsize=10)


def _draw_energy(ax: Axes, result: Comparison) -> None:
    energies = [(r.target, r.energy.uj_per_sample) for r in result.rows if r.energy is not None]
    if not energies:
        ax.axis("off")
        ax.text(0.5, 0.5, "no target has a published\nenergy cost model for this network", ha="center", va="center")
        return
    ax.bar([t for t, _ in energies], [e for _, e in energies], color="C1")
    for i, (_, e) in enumerate(energies):
        ax.text(i, e, f"{e:.3g} uJ", ha="center", va="bottom", fontsize=8)
    ax.set_yscale("log")
    ax.set_ylim(min(e for _, e in energies) / 3, max(e for _, e in energies) * 5)
    ax.set_ylabel("energy per sample, uJ (ESTIMATE, log)")
    ax.set_title("energy where a published cost model exists", fontsize=10)
