"""``snncc hpo``: the paper's two-step hyper-parameter search, hardware-aware, resumable (docs/hpo.md)."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from snncc.targets import DEFAULT_TARGET
from snncc.cli.app import app
from snncc.cli.paths import declares_paths
from snncc.cli.target_flags import with_target_flags

hpo_app = typer.Typer(
    help=(
        "Hyper-parameter search (the paper's two steps on Optuna): annealing over the nine "
        "hyper-parameters, then a grid over time_bin_size x nb_input_copies; every trial compiled "
        "for Loihi (cores, synaptic ops, ESTIMATED energy and delay). Studies resume where they "
        "stopped; several workers can share one storage."
    ),
    invoke_without_command=True,
    context_settings={"help_option_names": ["-h", "--help"]},
)
app.add_typer(hpo_app, name="hpo")


@hpo_app.callback()
def _hpo_group(ctx: typer.Context) -> None:
    if ctx.invoked_subcommand is None:  # `snncc hpo` alone: the help, exit 0
        from snncc.cli.output import console

        console.print(ctx.get_help())
        raise typer.Exit(0)


@hpo_app.command("run")
@with_target_flags("lower")
@declares_paths(inputs=("data",), outputs=("workdir",), study_storage=("storage", "workdir"))
def run_command(
    name: str = typer.Argument(..., help="Study name (step 2's study is NAME-grid). Rerun to resume."),
    data: Path = typer.Option(..., "--data", help="Directory of published Braille files (snncc data synth or Zenodo); an encoded .npz pins time_bin_size."),
    threshold: int = typer.Option(1, "--threshold", help="Sigma-delta threshold of the events (1, 2, 5, 10)."),
    step: str = typer.Option("both", "--step", help="anneal (step 1), grid (step 2, around step 1's best) or both."),
    trials: int = typer.Option(600, "--trials", help="Step 1's budget of trials (paper: 600)."),
    restarts: int = typer.Option(2, "--restarts", help="Evenly spaced re-initialisations of the annealing tuner (paper: 2)."),
    grid_span: int = typer.Option(1, "--grid-span", help="Step 2: rungs either side of step 1's best (1: a 3 x 3 grid)."),
    objectives: str = typer.Option("accuracy", "--objectives", help="Comma list of accuracy, energy, cores, synops, delay, emulated_accuracy; 'pareto' = accuracy and the target's front (loihi: energy, cores)."),
    ranges: Optional[List[str]] = typer.Option(None, "--range", help="Override a range, KEY=LOW:HIGH (or KEY=VALUE to fix it); repeatable."),
    model: str = typer.Option("rsnn", "--model", help="rsnn or ffsnn."),
    epochs: int = typer.Option(300, "--epochs", help="Epochs per trial (paper: 300)."),
    subset: Optional[int] = typer.Option(None, "--subset", help="Train and test on a seeded stratified subset of N samples."),
    seed: int = typer.Option(0, "--seed", help="Seed of the split, the initialisation and the sampler."),
    val_fraction: float = typer.Option(0.2, "--val-fraction", help="Share of the samples held out to select epochs and trials."),
    select: str = typer.Option("val", "--select", help="val (default) or test (the paper's choice: OPTIMISTIC accuracies)."),
    hidden: Optional[int] = typer.Option(None, "--hidden", help="Hidden neurons (default: the paper's 450)."),
    batch_size: int = typer.Option(128, "--batch-size", help="Batch size (paper: 128)."),
    energy_samples: int = typer.Option(16, "--energy-samples", help="Held-out samples emulated for the energy/delay ESTIMATE."),
    emulate: int = typer.Option(0, "--emulate", help="Also measure the bit-exact emulated accuracy on N held-out samples (0: off)."),
    pruner: str = typer.Option("median", "--pruner", help="median or none (single objective only)."),
    startup: int = typer.Option(3, "--startup", help="Annealing: prior draws after each (re)initialisation."),
    preset: bool = typer.Option(True, "--preset/--no-preset", help="Run the paper's preset for the threshold as step 1's first trial."),
    storage: Optional[str] = typer.Option(None, "--storage", help="Optuna storage URL (e.g. postgresql://user:pass@host/db); default sqlite in --dir."),
    workdir: Path = typer.Option(Path("hpo"), "--dir", help="Directory for the default SQLite storage and the trials' checkpoints."),
    device: str = typer.Option("auto", "--device", help="auto (CUDA when available), cpu, cuda or cuda:N."),
    threads: int = typer.Option(1, "--threads", help="Torch CPU threads."),
    heartbeat: int = typer.Option(30, "--heartbeat", help="Seconds between a running trial's heartbeats; a trial silent for 2x+1 is re-queued."),
    target: str = typer.Option(DEFAULT_TARGET, "--target", "-t", help="Target whose hardware figures cost each trial (its objectives: loihi energy, cores, ...; xylo neurons, feasible, real_time_margin)."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bars."),
    json_out: bool = typer.Option(False, "--json", help="Print the run summary as JSON."),
    target_options: dict = {},
) -> None:
    """Run or resume the search (step 1, step 2 or both) in one worker; start more workers on the same storage.

    The target options below are declared by the targets that take them; each trial is compiled with
    them (stored with the study's plan)."""
    from snncc.api import hpo_run
    from snncc.cli.hpo_view import RichStudyView
    from snncc.cli.output import console, err_console, print_json

    # Ctrl-C: the running trial is marked FAIL and re-queued (study.Interrupted, a KeyboardInterrupt);
    # the entry point prints its one line and exits with 130; rerunning the command continues
    result = hpo_run(name, data=data, threshold=threshold, step=step, trials=trials, restarts=restarts,
                     grid_span=grid_span, objectives=objectives, ranges=ranges, model=model, epochs=epochs,
                     subset=subset, seed=seed, val_fraction=val_fraction, select=select, hidden=hidden,
                     batch_size=batch_size, energy_samples=energy_samples, emulate=emulate, pruner=pruner,
                     startup=startup, preset=preset, storage=storage, workdir=workdir, device=device,
                     threads=threads, heartbeat=heartbeat, target=target, target_options=target_options,
                     view=None if (quiet or json_out) else RichStudyView(err_console))
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)


@hpo_app.command("report")
@declares_paths(outputs=("plot",), study_storage=("storage", "workdir"))
def report_command(
    study: str = typer.Argument(..., help="Study name."),
    storage: Optional[str] = typer.Option(None, "--storage", help="Optuna storage URL (default: the SQLite file in --dir)."),
    workdir: Path = typer.Option(Path("hpo"), "--dir", help="Directory of the default SQLite storage."),
    plot: Optional[Path] = typer.Option(None, "--output", "-o", help="Figure to write (PNG; default DIR/STUDY-front.png)."),
    no_plot: bool = typer.Option(False, "--no-plot", help="Do not draw the figure."),
    json_out: bool = typer.Option(False, "--json", help="Print the report as JSON."),
) -> None:
    """Best trials per objective, the Pareto front (accuracy, energy, cores) and the paper's presets."""
    from snncc.api import hpo_report
    from snncc.cli.output import console, print_json

    result = hpo_report(study, storage=storage, workdir=workdir, output=plot, no_plot=no_plot)
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)


@hpo_app.command("space")
def space_command(json_out: bool = typer.Option(False, "--json", help="Print as JSON.")) -> None:
    """The search space (our ranges) beside the paper's four presets."""
    from snncc.api import hpo_space
    from snncc.cli.output import console, print_json

    result = hpo_space()
    if json_out:
        print_json(result.as_dict())
    else:
        result.render_text(console)
