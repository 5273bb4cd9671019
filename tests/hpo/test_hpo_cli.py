"""``snncc hpo`` end to end on CPU: a study interrupted (Ctrl-C), killed (SIGKILL) and resumed loses
and repeats no trial; two workers share one storage; the report has the front with cores and energy."""

from __future__ import annotations

import json
import signal

import optuna
import pytest

from tests.hpo.helpers import run, start, states, tiny_args, trials, wait_until

COMPLETE, RUNNING, FAIL = optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.RUNNING, optuna.trial.TrialState.FAIL
optuna.logging.set_verbosity(optuna.logging.ERROR)


def _state(ts, state):
    return [t for t in ts if t.state == state]


def test_interrupted_killed_and_resumed_study_loses_and_repeats_nothing(braille_dir, tmp_path, capsys):
    from snncc.cli.main import run as cli

    work = tmp_path / "w"
    epochs = 12   # long enough that a poll finds a trial in the middle even on an idle machine
    args = ["hpo", "run", "s", "--step", "anneal", "--trials", "3", "--epochs", str(epochs), "--pruner", "none",
            *tiny_args(braille_dir, work)]

    def midway(min_complete):
        """``min_complete`` trials done and one RUNNING with some epochs reported and several still to go."""
        rows = states(work)
        return sum(state == "COMPLETE" for _, state, _ in rows) >= min_complete and any(
            state == "RUNNING" and epoch is not None and 1 <= epoch <= epochs - 4 for _, state, epoch in rows)

    # 1) Ctrl-C in the middle of a trial, after one finished: one line, exit 130, the trial re-queued
    p = start(args)
    wait_until(lambda: midway(1), p)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    assert p.returncode == 130, err
    assert err.strip().count("\n") == 0 and err.startswith("snncc: interrupted"), err
    # 2) SIGKILL in the middle of a later trial: it stays RUNNING until its heartbeat is stale
    p = start(args)
    wait_until(lambda: midway(2), p)
    p.kill()
    p.wait(timeout=30)
    assert _state(trials(work, "s"), RUNNING)
    # 3) the same command again finishes the study
    r = run(args)
    assert r.returncode == 0, r.stderr
    ts = trials(work, "s")
    done = _state(ts, COMPLETE)
    assert len(done) == 3 and not _state(ts, RUNNING) and not _state(ts, optuna.trial.TrialState.WAITING)
    failed = _state(ts, FAIL)
    assert len(failed) == 2                                # the Ctrl-C'd one and the killed one
    for f in failed:                                       # every interrupted trial was run again exactly once, to the end
        retries = [t for t in ts if t.system_attrs.get("retry_history", [None])[-1] == f.number]
        assert len(retries) == 1 and retries[0].params == f.params
        assert retries[0].state == COMPLETE or retries[0] in failed
    assert len({json.dumps(t.params, sort_keys=True) for t in done}) == 3      # no finished trial repeated
    for t in done:
        hw = t.user_attrs["outcome"]["hardware"]
        assert hw["cores"] >= 1 and hw["energy_uj_per_sample"] > 0 and hw["synaptic_ops_per_sample"] > 0
    # 4) the report: table, JSON and the figure; the front carries cores and energy
    capsys.readouterr()
    assert cli(["hpo", "report", "s", "--dir", str(work), "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["synthetic_data"] and rep["counts"]["complete"] == 3 and rep["front"]
    rows = {r["number"]: r for r in rep["rows"]}
    assert all(rows[n]["cores"] >= 1 and rows[n]["energy_uj"] > 0 for n in rep["front"])
    assert (work / "s-front.png").stat().st_size > 1000
    assert cli(["hpo", "report", "s", "--dir", str(work), "--no-plot"]) == 0
    text = capsys.readouterr().out
    assert "Pareto" in text and "paper" in text and "SYNTHETIC" in text


def test_two_workers_share_one_study(braille_dir, tmp_path):
    work = tmp_path / "w"
    work.mkdir()
    args = ["hpo", "run", "two", "--step", "both", "--trials", "3", "--epochs", "1", "--grid-span", "1",
            *tiny_args(braille_dir, work)]
    workers = [start(args), start(args)]
    for p in workers:
        out, err = p.communicate(timeout=240)
        assert p.returncode == 0, err
    for name, n in (("two", 3), ("two-grid", 2)):          # grid: time_bin_size pinned x copies 1..2
        ts = trials(work, name)
        done = _state(ts, COMPLETE)
        cancelled = [t for t in ts if t.user_attrs.get("over_budget")]   # the two workers' checks raced
        assert len(done) == n and len(ts) == n + len(cancelled), [(t.number, t.state) for t in ts]
        assert all(t.state == FAIL and "outcome" not in t.user_attrs for t in cancelled)
        assert len({json.dumps(t.params, sort_keys=True) for t in done}) == n   # no trial run twice
    ran_by = {t.user_attrs["worker"] for name in ("two", "two-grid") for t in trials(work, name) if t.state == COMPLETE}
    assert len(ran_by) == 2                                # both processes took trials


@pytest.mark.parametrize("extra, field", [
    (["--storage", "not-a-url"], "--storage"),
    (["--storage", "sqlite:////no/such/dir/x.db"], "--storage"),
    (["--range", "tau_mem=0.2:0.01"], "--range"),
    (["--objectives", "speed"], "--objectives"),
    (["--target", "xylo", "--objectives", "accuracy,energy"], "unknown objective 'energy' (known: accuracy, neurons"),
    (["--select", "train"], "--select"),
    (["--hidden", "1000000000"], "--hidden: 1,000,000,000 hidden neurons: the input weights"),   # not 192 GB
])
def test_bad_input_is_one_line_and_exit_2(braille_dir, tmp_path, capsys, extra, field):
    from snncc.cli.main import run as cli

    capsys.readouterr()
    code = cli(["hpo", "run", "bad", "--trials", "1", "--epochs", "1", *tiny_args(braille_dir, tmp_path / "w"), *extra])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and field in err, err


def test_unknown_study_is_one_line_and_exit_2(braille_dir, tmp_path, capsys):
    from snncc.cli.main import run as cli

    work = tmp_path / "w"
    capsys.readouterr()
    assert cli(["hpo", "report", "nope", "--dir", str(work)]) == 2        # no storage at all
    import optuna as o

    work.mkdir()
    o.create_study(study_name="other", storage=f"sqlite:///{work / 'hpo.sqlite3'}")
    capsys.readouterr()
    assert cli(["hpo", "report", "nope", "--dir", str(work)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no such study" in err and "other" in err


def test_hpo_alone_shows_help_and_space_lists_the_ranges_and_presets(capsys):
    from snncc.cli.main import run as cli

    capsys.readouterr()
    assert cli(["hpo"]) == 0 and "report" in capsys.readouterr().out
    assert cli(["hpo", "space", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d["space"]) == set(d["paper_presets"]["1"]) and "choice" in d["note"]


def _read_only_mount(directory) -> bool:
    """Bind ``directory`` onto itself read-only (root only); True if it worked."""
    import os
    import subprocess

    if os.geteuid() != 0:
        return False
    if subprocess.run(["mount", "--bind", str(directory), str(directory)], capture_output=True).returncode:
        return False
    if subprocess.run(["mount", "-o", "remount,ro,bind", str(directory)], capture_output=True).returncode:
        subprocess.run(["umount", str(directory)], capture_output=True)
        return False
    return True


def test_read_only_study_database_is_refused_in_one_line(braille_dir, tmp_path, capsys, monkeypatch):
    """A study database hpo run cannot write: one line naming the database file, exit 2, nothing changed.

    Read-only by permissions is tested as a non-root user only (root writes through a 0444 file; as
    root the same refusal is tested on a read-only bind mount where this machine allows mounting)."""
    import os
    import subprocess

    from snncc.cli.main import run as cli

    work = tmp_path / "w"
    work.mkdir()
    db = work / "hpo.sqlite3"
    optuna.create_study(study_name="other", storage=f"sqlite:///{db}")
    before = db.read_bytes()
    args = ["hpo", "run", "s", "--trials", "1", "--epochs", "1", "--step", "anneal", *tiny_args(braille_dir, work)]

    def refused(extra, needle):
        capsys.readouterr()
        code = cli(args + extra)
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and needle in err, err
        assert f": {db}: " in err, err          # the database file, not a sqlite:/// URL
        assert db.read_bytes() == before

    # opened read-only through SQLite's URI form: refused before anything is opened
    refused(["--storage", f"sqlite:///file:{db}?mode=ro&uri=true"], "--storage: is opened read-only")
    # the same database failing while the study is created (the up-front check bypassed): still one line
    monkeypatch.setattr("snncc.hpo.run.check_writable", lambda url, field: None)
    refused(["--storage", f"sqlite:///file:{db}?mode=ro&uri=true"], "--storage: the study's database failed (")
    monkeypatch.undo()
    if os.geteuid() != 0:
        os.chmod(db, 0o444)
        refused([], "--dir: is read-only")
        os.chmod(db, 0o644)
        os.chmod(work, 0o555)
        refused([], "--dir: its directory is read-only")
        os.chmod(work, 0o755)
    elif _read_only_mount(work):
        try:
            refused([], "--dir: is read-only")
        finally:
            subprocess.run(["umount", str(work)], capture_output=True)
    else:
        pytest.skip("read-only by permissions needs a non-root user, and mounting was refused here")


def test_a_split_no_trial_can_make_is_refused_before_any_trial(braille_dir, tmp_path, capsys):
    from snncc.cli.main import run as cli

    work = tmp_path / "w"
    capsys.readouterr()
    code = cli(["hpo", "run", "s", "--trials", "2", "--epochs", "1", "--subset", "60", "--step", "anneal",
                *tiny_args(braille_dir, work)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert f"{braille_dir}: labels: cannot split 60 samples stratified by class" in err
    assert trials(work, "s") == []


def test_a_study_whose_every_trial_failed_for_one_input_reason_exits_2(braille_dir, tmp_path, capsys, monkeypatch):
    """The same failure found in each trial (the up-front check bypassed here) ends the run with that reason."""
    from snncc.cli.main import run as cli

    monkeypatch.setattr("snncc.hpo.run.check_split", lambda plan, source: None, raising=False)
    work = tmp_path / "w"
    args = ["hpo", "run", "s", "--trials", "2", "--epochs", "1", "--subset", "60", "--step", "anneal",
            *tiny_args(braille_dir, work)]
    for _ in range(2):   # the run, then a rerun of the spent study: the same line
        capsys.readouterr()
        code = cli(args)
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1, err
        assert "labels: cannot split 60 samples stratified by class" in err
        assert "(every one of study s's 2 trial(s) failed so)" in err
        assert [t.state for t in trials(work, "s")] == [FAIL, FAIL]
