"""Inputs and outputs are declared per command, not guessed from the command line.

Every path parameter of every registered command is declared an input or an output
(``snncc.cli.paths.declares_paths``); a command re-run over its own earlier outputs replaces them;
an output that resolves to an input (after symlinks), to a file the command read from an input
directory, or a directory holding an input, is still refused and changes nothing.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from snncc_test_helpers import build_workspace, run_cli


def click_commands():
    """(command path, click command) of every registered command, groups' commands included."""
    import typer

    from snncc.cli.main import build_app

    found = []

    def walk(command, path):
        subcommands = getattr(command, "commands", None)
        if subcommands is None:
            found.append((path, command))
            return
        for name, sub in subcommands.items():
            walk(sub, f"{path} {name}")

    walk(typer.main.get_command(build_app()), "snncc")
    return found


def _is_path(annotation) -> bool:
    """A path type, alone or inside Optional/List/Union."""
    import os
    import typing

    if isinstance(annotation, type) and issubclass(annotation, os.PathLike):
        return True
    return any(_is_path(arg) for arg in typing.get_args(annotation))


def undeclared(command) -> list[str]:
    """The path parameters of a click command its declaration leaves out (and declared names it lacks):
    a parameter annotated as a path, or a study's ``storage`` URL."""
    import inspect

    from snncc.cli.paths import declaration_of

    declaration = declaration_of(command.callback)
    declared = declaration.names() if declaration is not None else set()
    parameters = inspect.signature(command.callback, eval_str=True).parameters
    problems = []
    for name, parameter in parameters.items():
        if (_is_path(parameter.annotation) or name == "storage") and name not in declared:
            problems.append(name)
    problems += [f"{name}: declared but no such parameter" for name in sorted(declared - set(parameters))]
    return problems


def test_every_path_parameter_of_every_command_is_declared():
    commands = click_commands()
    assert len(commands) >= 17      # compile ... hpo space: every verb is registered
    missing = {path: problems for path, command in commands if (problems := undeclared(command))}
    assert not missing, f"path parameters without an input/output declaration: {missing}"


def test_the_declaration_check_finds_an_undeclared_path_parameter():
    """The check above can fail: a command with an undeclared path (or a declared name it lacks) is caught."""
    import typer

    from snncc.cli.paths import declares_paths

    app = typer.Typer()

    @app.command("one")
    @declares_paths(inputs=("source",))
    def one(source: Path = typer.Argument(...), plot: Path = typer.Option(None, "--plot")) -> None:
        pass

    @app.command("two")
    @declares_paths(inputs=("source", "gone"))
    def two(source: Path = typer.Argument(...)) -> None:
        pass

    group = typer.main.get_command(app)
    assert undeclared(group.commands["one"]) == ["plot"]
    assert undeclared(group.commands["two"]) == ["gone: declared but no such parameter"]


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    d = tmp_path_factory.mktemp("declared")
    build_workspace(d)
    return d


TINY_HPO = ["--data", "br", "--threshold", "1", "--step", "anneal", "--trials", "1", "--epochs", "1",
            "--hidden", "8", "--range", "time_bin_size=10", "--range", "nb_input_copies=1", "--energy-samples", "2",
            "--batch-size", "64", "--startup", "1", "--no-preset", "--pruner", "none", "--select", "test",
            "--quiet", "--device", "cpu", "--dir", "h"]

# every command that writes something, each output given by its long option (the spelling that was
# taken for an input before outputs were declared)
RERUNS = {
    "data synth": ["data", "synth", "--out", "syn", "-n", "1", "--thresholds", "1"],
    "data encode": ["data", "encode", "br", "--out", "ev2.npz", "--threshold", "1"],
    "data frames": ["data", "frames", "br", "--out", "fr.npz"],
    "data analyse": ["data", "analyse", "br", "--figures", "figs", "--thresholds", "1", "--no-svm", "--no-event-svm",
                     "--pca-step", "0"],
    "train": ["train", "rsnn", "--data", "ev.npz", "--epochs", "1", "--output", "t.pt", "--quiet"],
    "compile loihi": ["compile", "m.pt", "--target", "loihi", "--output", "b2.net"],
    "compile jetson": ["compile", "m.pt", "--target", "jetson", "--output", "jet2", "--time-steps", "20"],
    "emulate": ["emulate", "b.net", "--input", "spikes.npy", "--output", "o.npz"],
    "map": ["map", "b.net", "--plot", "cores.png"],
    "export": ["export", "m.pt", "--output", "m.nir"],
    "run": ["run", "jet", "--input", "x.npy", "--output", "r.npz"],
    "analyse ttc": ["analyse", "ttc", "m.pt", "--data", "ev.npz", "--split", "all", "--output", "ttc.json",
                    "--figure", "ttc.png"],
    "hpo run": ["hpo", "run", "s", *TINY_HPO],
    "hpo report": ["hpo", "report", "s", "--dir", "h", "--output", "front.png"],
}


@pytest.mark.parametrize("name", list(RERUNS))
def test_a_command_rerun_over_its_own_outputs_replaces_them(workspace, capsys, monkeypatch, name):
    monkeypatch.chdir(workspace)
    if name == "hpo report" and not (workspace / "h" / "hpo.sqlite3").exists():
        assert run_cli(["hpo", "run", "s", *TINY_HPO], capsys)[0] == 0
    for attempt in (1, 2):
        code, _, err = run_cli(RERUNS[name], capsys)
        assert code == 0, f"run {attempt} of snncc {name}: {err}"


def _refused(args, capsys, says: str) -> None:
    code, _, err = run_cli(args, capsys)
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and lines[0].startswith("snncc: error: "), err
    assert says in lines[0], lines[0]


def _contents(directory) -> dict:
    return {p.relative_to(directory).as_posix(): (p.is_symlink(), p.read_bytes() if p.is_file() else None)
            for p in sorted(directory.rglob("*"))}


def test_an_output_resolving_to_an_input_is_refused(workspace, tmp_path, capsys, monkeypatch):
    for name in ("br", "ev.npz", "m.pt", "b.net", "jet", "spikes.npy", "x.npy"):
        (shutil.copytree if (workspace / name).is_dir() else shutil.copy)(workspace / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "link.png").symlink_to(tmp_path / "b.net")
    (tmp_path / "link.npz").symlink_to(tmp_path / "br" / "data_braille_letters_raw.pkl")
    (tmp_path / "holder").mkdir()
    shutil.copy(tmp_path / "m.pt", tmp_path / "holder" / "m.pt")
    before = _contents(tmp_path)
    cases = [
        (["map", "b.net", "--plot", "link.png"], "is an input of this command"),          # a symlink to the input
        (["emulate", "b.net", "--input", "spikes.npy", "--output", "spikes.npy"], "is an input of this command"),
        (["train", "rsnn", "--data", "ev.npz", "--epochs", "1", "--output", "ev.npz"], "is an input of this command"),
        (["analyse", "ttc", "m.pt", "--data", "ev.npz", "--split", "all", "--output", "m.pt"],
         "is an input of this command"),
        # files read from inside an input directory are inputs too
        (["data", "encode", "br", "--threshold", "1", "--out", "br/data_braille_letters_th_1.pkl"],
         "is an input of this command"),
        (["data", "encode", "br", "--threshold", "1", "--from", "raw", "--out", "link.npz"],
         "is an input of this command"),
        (["data", "frames", "br", "--out", "br/SYNTHETIC.json"], "is an input of this command"),
        (["run", "jet", "--input", "x.npy", "--output", "jet/step.onnx"], "is an input of this command"),
        # a directory output that holds an input
        (["compile", "holder/m.pt", "--target", "jetson", "--output", "holder", "--time-steps", "20"],
         "contains an input of this command"),
    ]
    for args, says in cases:
        _refused(args, capsys, says)
        assert _contents(tmp_path) == before, args
