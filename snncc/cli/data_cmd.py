"""``snncc data``: Braille data — generate (synthetic), sigma-delta encode, analyse."""

from __future__ import annotations

import json
from contextlib import contextmanager
from dataclasses import asdict
from pathlib import Path
from typing import Iterator, Optional

import numpy as np
import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from snncc.cli.app import app
from snncc.cli.output import console, err_console, print_json
from snncc.errors import SnnccError

data_app = typer.Typer(
    help=(
        "Braille data: generate the calibrated synthetic set in the published Zenodo formats, "
        "sigma-delta encode and time-bin it into model inputs, and run the paper's encoding and "
        "SVM analyses. Real Zenodo files (both releases) work everywhere a directory or .pkl is asked."
    ),
    invoke_without_command=True,
    context_settings={"help_option_names": ["-h", "--help"]},
)
app.add_typer(data_app, name="data")


@data_app.callback()
def _data_group(ctx: typer.Context) -> None:
    if ctx.invoked_subcommand is None:  # `snncc data` alone: the help, exit 0
        console.print(ctx.get_help())
        raise typer.Exit(0)


@contextmanager
def _progress(enabled: bool = True) -> Iterator[Progress]:
    bar = Progress(
        TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
        console=err_console, transient=True, disable=not enabled,
    )
    with bar:
        yield bar


def _parse_thresholds(text: str) -> list[float]:
    try:
        ths = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise SnnccError(f"expected comma-separated numbers, got {text!r}", field="--thresholds") from None
    if not ths or any(not np.isfinite(t) or t <= 0 for t in ths):
        raise SnnccError("thresholds must be positive numbers", field="--thresholds")
    return sorted(set(ths))


def _fmt_th(th: float) -> str:
    return f"{th:g}"


# --------------------------------------------------------------------------- synth


@data_app.command("synth")
def synth_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Directory to write the data set into (created)."),
    repetitions: int = typer.Option(200, "--repetitions", "-n", min=1, help="Repetitions per letter (27 letters)."),
    seed: int = typer.Option(0, "--seed", help="Random seed; the same seed gives byte-identical files."),
    release: int = typer.Option(1, "--release", min=1, max=2,
                                help="Container of the published release: 1 = list of dicts (Zenodo 6556273), "
                                     "2 = pandas DataFrame (Zenodo 7050094)."),
    thresholds: str = typer.Option("1,2,5,10", "--thresholds", help="Event files to write (sigma-delta thresholds)."),
    generator_version: int = typer.Option(2, "--generator-version", min=1, max=2,
                                          help="2 = calibrated to task difficulty (issue 15, default); "
                                               "1 = the earlier, much easier generator."),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Generate the SYNTHETIC Braille set (physical model, calibrated to the paper's analyses).

    Writes DIR/data_braille_letters_raw.pkl (raw 8-bit frames, 255 at rest, 54 frames at 40 Hz)
    and DIR/data_braille_letters_th_{1,2,5,10}.pkl (sigma-delta events of the inverted frames) in
    the published layouts, plus DIR/SYNTHETIC.json (generator parameters, seed). See
    docs/braille_synthetic.md for the model and its calibration.
    """
    from snncc.data import formats, synth
    from snncc.data.sigma_delta import encode
    from snncc.data.sources import MARKER

    ths = _parse_thresholds(thresholds)
    n_total = 27 * repetitions
    with _progress(not json_out) as bar:
        task = bar.add_task("generating frames", total=n_total)
        raw, labels = synth.generate(repetitions, seed, progress=lambda k: bar.update(task, completed=k),
                                     version=generator_version)
        wtask = bar.add_task("encoding and writing", total=1 + len(ths))
        formats.write_raw(out / formats.RAW_NAME, raw, labels, release=release)
        bar.advance(wtask)
        x = 255 - raw.astype(np.int64)
        counts = {}
        for th in ths:
            ev = encode(x, th)
            counts[_fmt_th(th)] = len(ev) / (raw.shape[0] * raw.shape[2])
            formats.write_events(out / formats.events_name(th), ev, labels, release=release)
            bar.advance(wtask)
    info = {
        "synthetic": True,
        "generator": "snncc.data.synth (physical model, calibrated; see docs/braille_synthetic.md)",
        "generator_version": generator_version,
        "seed": seed,
        "repetitions": repetitions,
        "release": release,
        "samples": int(raw.shape[0]),
        "frames": int(raw.shape[1]),
        "thresholds": ths,
        "params": synth.params_dict(version=generator_version),
    }
    from snncc.atomic import atomic_path

    with atomic_path(out / MARKER) as tmp:
        tmp.write_text(json.dumps(info, indent=2, sort_keys=True) + "\n")
    record = {"out": str(out), "samples": int(raw.shape[0]), "frames": int(raw.shape[1]),
              "files": [formats.RAW_NAME] + [formats.events_name(t) for t in ths] + [MARKER],
              "mean_events_per_taxel": counts, "seed": seed, "release": release, "synthetic": True,
              "generator_version": generator_version}
    if json_out:
        print_json(record)
    else:
        console.print(f"wrote {raw.shape[0]} synthetic samples ({repetitions} x 27 letters, seed {seed}) to {out}")
        console.print("mean events per taxel and sample: "
                      + ", ".join(f"th {k}: {v:.1f}" for k, v in counts.items()))


# --------------------------------------------------------------------------- encode


@data_app.command("encode")
def encode_cmd(
    src: Path = typer.Argument(..., help="A directory with the published files, or one .pkl (raw frames or events)."),
    out: Path = typer.Option(..., "--out", "-o", help="Output data set (.npz): inputs (N, T, 24) uint8, labels, meta."),
    threshold: Optional[float] = typer.Option(None, "--threshold", "-t",
                                              help="Sigma-delta threshold (1, 2, 5, 10 in the paper). For an event "
                                                   "file it defaults to the one in its name."),
    bin_ms: float = typer.Option(5.0, "--bin", "-b", help="time_bin_size in ms (paper: 5 for th 1 and 10, 3 for th 2 and 5)."),
    prefer: str = typer.Option("auto", "--from",
                               help="auto: the directory's event file for this threshold if present, else encode "
                                    "the raw frames; 'events' or 'raw' to insist."),
    record_ms_opt: Optional[float] = typer.Option(None, "--record-ms",
                                                  help="Recording length in ms (bins = ceil(record/bin)). Default: "
                                                       "frames x 25 ms of the raw frames (also for event files "
                                                       "beside a raw file), else 1350."),
    split_test: Optional[float] = typer.Option(None, "--split-test", min=0.01, max=0.99,
                                               help="Also write OUT_train.npz / OUT_test.npz, a stratified split "
                                                    "with this test fraction (e.g. 0.2)."),
    seed: int = typer.Option(0, "--seed", help="Seed of --split-test."),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Sigma-delta encode and time-bin Braille data into the model input file.

    Events follow the authors' rule exactly (reference starts at x[0], one event per threshold step,
    linearly interpolated times, no resampling) on inverted frames; bins are
    numpy.round(1000*t/bin) (round half to even), binary, channel = 2*taxel + polarity, 24
    channels, input copies NOT applied (the training code tiles them).
    """
    from snncc.data.encoding import encode_events, write_with_split

    with _progress(not json_out) as bar:
        task = bar.add_task("loading / encoding", total=2)
        encoded = encode_events(src, threshold, bin_ms, prefer, record_ms_opt, progress=lambda: bar.advance(task))
        bar.advance(task)
    written = write_with_split(out, encoded, split_test, seed)
    record = encoded.summary(written)
    if json_out:
        print_json(record)
        return
    inputs, meta = encoded.inputs, encoded.meta
    console.print(f"{inputs.shape[0]} samples x {inputs.shape[1]} bins x 24 channels (th {meta['threshold']:g}, "
                  f"bin {bin_ms:g} ms) -> {', '.join(written)}")
    before, after = meta["events_before_binning"], meta["events_after_binning"]
    lost = 100.0 * (1 - after / before) if before else 0.0
    console.print(f"events: {before} before binning, {after} after ({lost:.1f} % merged)"
                  + ("   (synthetic data)" if meta["synthetic"] else ""))


@data_app.command("frames")
def frames_cmd(
    src: Path = typer.Argument(..., help="A directory with data_braille_letters_raw.pkl, or that .pkl."),
    out: Path = typer.Option(..., "--out", "-o", help="Output data set (.npz): inputs (N, T, 12) float32."),
    split_test: Optional[float] = typer.Option(None, "--split-test", min=0.01, max=0.99,
                                               help="Also write a stratified OUT_train / OUT_test split."),
    seed: int = typer.Option(0, "--seed", help="Seed of --split-test."),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Write the inverted frames (0 = rest, 255 = full load) as a frame data set for the LSTM."""
    from snncc.data.encoding import frame_set, write_with_split

    encoded = frame_set(src)
    written = write_with_split(out, encoded, split_test, seed)
    if json_out:
        print_json(encoded.summary(written))
    else:
        n, t = encoded.inputs.shape[:2]
        console.print(f"{n} samples x {t} frames x 12 taxels -> {', '.join(written)}")


# --------------------------------------------------------------------------- analyse


@data_app.command("analyse")
def analyse_cmd(
    src: Path = typer.Argument(..., help="A directory with the published files (raw frames required)."),
    json_out: bool = typer.Option(False, "--json", help="Print the full report as JSON."),
    figures: Optional[Path] = typer.Option(None, "--figures", help="Write PNG figures into this directory."),
    thresholds: str = typer.Option("1,2,5,10", "--thresholds", help="Thresholds of the encoding table."),
    svm: bool = typer.Option(True, "--svm/--no-svm", help="Run the frame SVMs (raw, time collapsed)."),
    pca_step: int = typer.Option(6, "--pca-step", min=0,
                                 help="PCA-12 SVM every N frames (0 = skip the accuracy-vs-frames curve)."),
    event_svm: bool = typer.Option(True, "--event-svm/--no-event-svm", help="Run the SVMs on binned events."),
    event_threshold: float = typer.Option(1.0, "--event-threshold", help="Threshold of the event SVMs (not stated in the paper)."),
    event_bin: float = typer.Option(5.0, "--event-bin", help="Bin size (ms) of the event SVMs (not stated in the paper)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the cross-validation folds."),
    jobs: int = typer.Option(2, "--jobs", "-j", min=1, help="Parallel CV folds."),
) -> None:
    """The paper's encoding table and linear-SVM analyses, beside the paper's numbers.

    Encoding (per threshold): mean events per taxel and sample, compression vs th 1, reconstruction
    MSE before and after binning (paper's bin sizes), events lost to binning, share of
    inter-spike intervals below 1 ms. SVMs (scikit-learn OneVsRest LinearSVC, 5-fold CV): raw
    frames, time collapsed, PCA-12 over a growing number of frames, binned events with all bins vs
    spatial sums. On a synthetic set it also checks the calibration targets.
    """
    from snncc.data import analysis, calibration, figures as figs, formats, sources
    from snncc.data.binning import bin_events, binned_reconstruction, n_bins_for, record_ms
    from snncc.data.sigma_delta import reconstruct

    from snncc.data.encoding import load_raw_frames

    ths = _parse_thresholds(thresholds)
    raw_path, rs = load_raw_frames(src, f"the analysis needs the raw frames ({formats.RAW_NAME})")
    x = rs.inverted()
    labels = rs.labels
    n, t, c = x.shape
    syn = sources.synthetic_info(raw_path)
    from snncc.data.sigma_delta import encode

    with _progress(not json_out) as bar:
        steps = len(ths) * 2 + (2 if svm else 0) + (2 if event_svm else 0)
        frame_counts: list[int] = []
        if pca_step:
            frame_counts = sorted(set(list(range(1, t + 1, pca_step)) + [t]))
            steps += len(frame_counts)
        task = bar.add_task("analysing", total=steps)

        def note(desc: str) -> None:
            bar.update(task, description=desc)

        events_by_th = {}
        from_files = {}
        for th in ths:
            note(f"events th {th:g}")
            p = sources.events_file(src, th) if src.is_dir() else None
            if p is not None:
                es = formats.load_events(p)
                if es.events.n_samples != n or not np.array_equal(es.labels, labels):
                    raise SnnccError("samples or letters differ from the raw-frame file", file=str(p),
                                     field="letter")
                events_by_th[th] = es.events
                from_files[_fmt_th(th)] = str(p)
            else:
                events_by_th[th] = encode(x, th)
                from_files[_fmt_th(th)] = "encoded from raw frames"
            bar.advance(task)
        note("encoding table")
        rows = []
        base = len(events_by_th[ths[0]]) / (n * c)
        for th in ths:
            b = analysis.PAPER_BIN_MS.get(int(th), 5) if float(th).is_integer() else 5
            try:
                rows.append(analysis.encoding_row(x, events_by_th[th], th, b, base))
            except SnnccError as err:
                raise err.with_file(from_files[_fmt_th(th)])
            bar.advance(task)
        vs_bin = analysis.events_vs_bin_size(x.shape, events_by_th)
        std_events = event_threshold == 1 and event_bin == 5
        note("the paper's figures: frame SVMs under each protocol, event statistics")
        paper_figs = calibration.calibration_figures(x, labels, seed=seed, n_jobs=jobs, svm=svm,
                                                     event_svm=event_svm and std_events, progress=note)
        svm_res = paper_figs.svm_results() if svm else {}
        bar.advance(task, 2 if svm else 0)
        pca_points = []
        for k in frame_counts:
            note(f"PCA-12 SVM, first {k} frames")
            pca_points += analysis.svm_pca_vs_frames(x, labels, [k], seed=seed, n_jobs=jobs)
            bar.advance(task)
        ev_svm = paper_figs.event_svm_results() if event_svm and std_events else {}
        if event_svm and not std_events:
            ev = events_by_th.get(event_threshold)
            if ev is None:
                ev = encode(x, event_threshold)
            binned = bin_events(ev, event_bin, n_bins_for(record_ms(t), event_bin))
            note("SVM, binned events")
            ev_svm = analysis.svm_events(binned, labels, seed=seed, n_jobs=jobs)
            bar.advance(task, 2)
    calib = [f.as_dict() for f in paper_figs.figures] if syn else []
    calib_note = None
    if syn and n < 27 * 200:
        calib_note = (f"the targets refer to the default set (200 repetitions per letter); with {n} samples "
                      "the SVM accuracies are lower (fewer training samples), the event counts are not")
    fig_files = []
    if figures is not None:
        i, k = 0, 1
        if n:
            # the sample/taxel with the most activity at th 1 shows the encoding best
            counts = events_by_th[ths[0]].counts()
            i, k = np.unravel_index(int(np.argmax(counts)), counts.shape)
        curves = {}
        for th in ths:
            ev = events_by_th[th].select(np.array([i]))
            before = reconstruct(ev, x[i:i + 1, 0, :], t, th)[0, :, k]
            b = analysis.PAPER_BIN_MS.get(int(th), 5) if float(th).is_integer() else 5
            bb = bin_events(ev, b, n_bins_for(record_ms(t), b))
            after = binned_reconstruction(bb, x[i:i + 1, 0, :], t, b, th)[0, :, k]
            curves[th] = (before, after)
        from snncc.data.letters import CLASSES

        fig_files.append(str(figs.reconstruction(figures / "reconstruction.png", x[i, :, k], curves,
                                                 f"sample {i} ('{CLASSES[labels[i]]}'), taxel {k}")))
        fig_files.append(str(figs.events_vs_bin_size(figures / "events_vs_bin_size.png", vs_bin)))
        if pca_points:
            fig_files.append(str(figs.svm_vs_frames(figures / "svm_vs_frames.png", pca_points,
                                                    svm_res["raw"].mean_pct if "raw" in svm_res else None)))
    report = {
        "source": str(src), "samples": n, "frames": t, "taxels": c, "synthetic": syn is not None,
        "events_from": from_files,
        "encoding": [asdict(r) for r in rows],
        "events_vs_bin_size": {_fmt_th(k): v for k, v in vs_bin.items()},
        "svm_frames": {k: asdict(v) for k, v in svm_res.items()},
        "svm_pca_vs_frames": pca_points,
        "svm_events": ({"threshold": event_threshold, "bin_ms": event_bin,
                        **{k: asdict(v) for k, v in ev_svm.items()}} if ev_svm else {}),
        "paper": analysis.PAPER,
        "paper_figures": paper_figs.as_dict(),
        "calibration": calib,
        "calibration_note": calib_note,
        "figures": fig_files,
    }
    if json_out:
        print_json(report)
        return
    _print_report(report)


def _print_report(r: dict) -> None:
    from snncc.data.analysis import PAPER

    tag = "SYNTHETIC data" if r["synthetic"] else "data"
    console.print(f"[bold]Braille encoding analysis[/bold] — {r['samples']} samples x {r['frames']} frames x "
                  f"{r['taxels']} taxels ({tag}: {r['source']})")
    tab = Table(title="Encoding: events per taxel and sample (paper's real-data values below each row)")
    for col in ("th", "events", "ratio", "MSE", "bin", "binned", "ratio b.", "MSE b.", "lost %", "ISI<1ms %"):
        tab.add_column(col, justify="right")
    cols = ("events", "compression", "mse", None, "events_binned", "compression_binned", "mse_binned", None,
            "isi_below_1ms_pct")

    def paper_row(th):
        if not float(th).is_integer() or int(th) not in PAPER["events"]:
            return None
        return ["paper"] + [("" if k is None else f"{PAPER[k][int(th)]:g}") for k in cols]

    for row in r["encoding"]:
        th = row["threshold"]
        tab.add_row(f"{th:g}", f"{row['events']:.1f}", f"{row['compression']:.1f}", f"{row['mse']:.2f}",
                    f"{row['bin_ms']:g}", f"{row['events_binned']:.1f}", f"{row['compression_binned']:.1f}",
                    f"{row['mse_binned']:.1f}", f"{row['lost_pct']:.1f}", f"{row['isi_below_1ms_pct']:.2f}")
        pr = paper_row(th)
        if pr:
            tab.add_row(*pr, style="dim")
    console.print(tab)
    if r["svm_frames"] or r["svm_events"]:
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
        console.print(st)
    if r["svm_pca_vs_frames"]:
        pts = ", ".join(f"{p['seconds']:.2f}s {p['mean_pct']:.0f}%" for p in r["svm_pca_vs_frames"])
        console.print(f"PCA-12 SVM vs frames used: {pts}")
    if r.get("paper_figures"):
        title = "The paper's figures: measured vs paper" + (" (calibration of the synthetic generator)"
                                                               if r["synthetic"] else "")
        ct = Table(title=title)
        for col in ("figure", "measured", "paper", "tolerance", "ok", "protocol"):
            ct.add_column(col, justify="right" if col != "protocol" else "left")
        for row in r["paper_figures"]["figures"]:
            ct.add_row(row["name"], f"{row['measured']:.1f}", f"{row['paper']:g}", row["tolerance"],
                       "yes" if row["ok"] else "[red]NO[/red]", row["protocol"])
        console.print(ct)
        if r.get("calibration_note"):
            console.print(f"note: {r['calibration_note']}")
    for f in r["figures"]:
        console.print(f"figure: {f}")
