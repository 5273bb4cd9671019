"""The ``snncc data analyse`` report (``analysis_report.analyse_braille``) as rich text, beside the paper's values."""

from __future__ import annotations

from snncc.errors import one_line


def _encoding_table(r: dict):
    from rich.table import Table

    from snncc.data.analysis import PAPER

    tab = Table(title="Encoding: events per taxel and sample (paper's real-data values below each row)")
    for col in ("th", "events", "ratio", "MSE", "bin", "binned", "ratio b.", "MSE b.", "lost %", "ISI<1ms %"):
        tab.add_column(col, justify="right")
    cols = ("events", "compression", "mse", None, "events_binned", "compression_binned", "mse_binned", None,
            "isi_below_1ms_pct")
    for row in r["encoding"]:
        th = row["threshold"]
        tab.add_row(f"{th:g}", f"{row['events']:.1f}", f"{row['compression']:.1f}", f"{row['mse']:.2f}",
                    f"{row['bin_ms']:g}", f"{row['events_binned']:.1f}", f"{row['compression_binned']:.1f}",
                    f"{row['mse_binned']:.1f}", f"{row['lost_pct']:.1f}", f"{row['isi_below_1ms_pct']:.2f}")
        if float(th).is_integer() and int(th) in PAPER["events"]:
            tab.add_row("paper", *[("" if k is None else f"{PAPER[k][int(th)]:g}") for k in cols], style="dim")
    return tab


def _svm_table(r: dict):
    from rich.table import Table

    from snncc.data.analysis import PAPER

    st = Table(title="Linear SVM, one-vs-rest, 5-fold CV")
    for col in ("features", "accuracy %", "paper %"):
        st.add_column(col, justify="right")
    names = {"raw": ("raw frames (all), primary protocol", PAPER["svm_raw"]),
             "collapsed": ("time collapsed, primary protocol", PAPER["svm_collapsed"])}
    for k, v in r["svm_frames"].items():
        st.add_row(names[k][0], f"{v['mean_pct']:.1f} +- {v['std_pct']:.1f}", f"{names[k][1]:g}")
    if r["svm_events"]:
        e = r["svm_events"]
        st.add_row(f"events th {e['threshold']:g} bin {e['bin_ms']:g} ms, all bins",
                   f"{e['all_bins']['mean_pct']:.1f} +- {e['all_bins']['std_pct']:.1f}", f"{PAPER['svm_events_all_bins']:g}")
        st.add_row("events, spatial sums only", f"{e['spatial']['mean_pct']:.1f} +- {e['spatial']['std_pct']:.1f}",
                   f"{PAPER['svm_events_spatial']:g}")
    return st


def _figures_table(r: dict):
    from rich.table import Table

    title = "The paper's figures: measured vs paper" + (" (calibration of the synthetic generator)"
                                                       if r["synthetic"] else "")
    ct = Table(title=title)
    for col in ("figure", "measured", "paper", "tolerance", "ok", "protocol"):
        ct.add_column(col, justify="right" if col != "protocol" else "left")
    for row in r["paper_figures"]["figures"]:
        ct.add_row(row["name"], f"{row['measured']:.1f}", f"{row['paper']:g}", row["tolerance"],
                   "yes" if row["ok"] else "[red]NO[/red]", row["protocol"])
    return ct


def render_analysis(r: dict, console) -> None:
    """Encoding table with the paper's row under each threshold, the SVMs, the PCA curve, the
    paper's figures (measured, paper, tolerance, met) and the figure files."""
    tag = "SYNTHETIC data" if r["synthetic"] else "data"
    console.print(f"[bold]Braille encoding analysis[/bold] — {r['samples']} samples x {r['frames']} frames x "
                  f"{r['taxels']} taxels ({tag}: {r['source']})")
    console.print(_encoding_table(r))
    if r["svm_frames"] or r["svm_events"]:
        console.print(_svm_table(r))
    if r["svm_pca_vs_frames"]:
        pts = ", ".join(f"{p['seconds']:.2f}s {p['mean_pct']:.0f}%" for p in r["svm_pca_vs_frames"])
        console.print(f"PCA-12 SVM vs frames used: {pts}")
    if r.get("paper_figures"):
        console.print(_figures_table(r))
        if r.get("calibration_note"):
            console.print(f"note: {r['calibration_note']}")
    for f in r["figures"]:
        console.print(f"figure: {one_line(f)}", markup=False)
