"""``snncc data``: Braille data — generate (synthetic), sigma-delta encode, analyse."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.output import bar_columns, console, print_json, progress_bar

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


def _progress(enabled: bool = True):
    """The verb's ``progress(done, total, phase)``: a transient bar on stderr (none when not enabled)."""
    return progress_bar(*bar_columns(), disable=not enabled)


def _show(record, json_out: bool) -> None:
    if json_out:
        print_json(record.as_dict())
    else:
        record.render_text(console)


@data_app.command("synth")
@declares_paths(outputs=("out",))
def synth_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="Directory to write the data set into (created)."),
    repetitions: int = typer.Option(200, "--repetitions", "-n", min=1, help="Repetitions per letter (27 letters)."),
    seed: int = typer.Option(0, "--seed", help="Random seed; the same seed gives byte-identical files."),
    release: int = typer.Option(1, "--release", min=1, max=2,
                                help="Container of the published release: 1 = list of dicts (Zenodo 6556273), "
                                     "2 = pandas DataFrame (Zenodo 7050094)."),
    thresholds: str = typer.Option("1,2,5,10", "--thresholds", help="Event files to write (sigma-delta thresholds)."),
    generator_version: int = typer.Option(2, "--generator-version", min=1, max=2,
                                          help="2 = calibrated to task difficulty (default; docs/braille_synthetic.md); "
                                               "1 = the earlier, much easier generator."),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Generate the SYNTHETIC Braille set (physical model, calibrated to the paper's analyses).

    Writes DIR/data_braille_letters_raw.pkl (raw 8-bit frames, 255 at rest, 54 frames at 40 Hz)
    and DIR/data_braille_letters_th_{1,2,5,10}.pkl (sigma-delta events of the inverted frames) in
    the published layouts, plus DIR/SYNTHETIC.json (generator parameters, seed). See
    docs/braille_synthetic.md for the model and its calibration.
    """
    from snncc.api import data_synth

    with _progress(not json_out) as bar:
        record = data_synth(out=out, repetitions=repetitions, seed=seed, release=release, thresholds=thresholds,
                            generator_version=generator_version, progress=bar)
    _show(record, json_out)


@data_app.command("nir")
@declares_paths(outputs=("out",))
def nir_cmd(
    out: Path = typer.Option(..., "--out", "-o", help="The .npz to write (inputs, labels, classes; atomically)."),
    samples: int = typer.Option(700, "--samples", "-n", help="Samples, balanced over the 7 letters."),
    seed: int = typer.Option(0, "--seed", help="Random seed; the same seed gives the same samples."),
    steps: int = typer.Option(256, "--steps", help="Steps per sample (the NIR paper's: 256)."),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """SYNTHETIC Braille letters in the NIR paper's layout (Space, A, E, I, O, U, Y; 12 channels, ON and OFF merged; 256 steps), labelled, for check --data and compare --data on the NIR Braille graphs."""
    from snncc.api import data_nir

    _show(data_nir(out=out, samples=samples, seed=seed, steps=steps), json_out)


@data_app.command("encode")
@declares_paths(inputs=("src",), outputs=("out",))
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
    from snncc.api import data_encode

    with _progress(not json_out) as bar:
        record = data_encode(src, out=out, threshold=threshold, bin_ms=bin_ms, prefer=prefer,
                             record_ms=record_ms_opt, split_test=split_test, seed=seed, progress=bar)
    _show(record, json_out)


@data_app.command("frames")
@declares_paths(inputs=("src",), outputs=("out",))
def frames_cmd(
    src: Path = typer.Argument(..., help="A directory with data_braille_letters_raw.pkl, or that .pkl."),
    out: Path = typer.Option(..., "--out", "-o", help="Output data set (.npz): inputs (N, T, 12) float32."),
    split_test: Optional[float] = typer.Option(None, "--split-test", min=0.01, max=0.99,
                                               help="Also write a stratified OUT_train / OUT_test split."),
    seed: int = typer.Option(0, "--seed", help="Seed of --split-test."),
    json_out: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Write the inverted frames (0 = rest, 255 = full load) as a frame data set for the LSTM."""
    from snncc.api import data_frames

    _show(data_frames(src, out=out, split_test=split_test, seed=seed), json_out)


@data_app.command("analyse")
@declares_paths(inputs=("src",), outputs=("figures",))
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
    from snncc.api import data_analyse

    with _progress(not json_out) as bar:
        record = data_analyse(src, figures=figures, thresholds=thresholds, svm=svm, pca_step=pca_step,
                              event_svm=event_svm, event_threshold=event_threshold, event_bin=event_bin,
                              seed=seed, jobs=jobs, progress=bar)
    _show(record, json_out)
