"""Hostile Xylo artefacts (issue 39): a good artefact's copies tampered one way each. Every command that reads one
ends in one line ``snncc: error: <file>: <field>: <rule>``, exit status 2, no traceback, and reads nothing outside
the artefact (a file reached through a link is never opened: the refusal comes from the link itself)."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from snncc.targets.kit.writing import npz_bytes
from snncc_test_helpers import run_cli

NIR = Path(__file__).resolve().parents[2] / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"
MODEL = ["--dt", "1e-4", "--reset", "subtract"]


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> Path:
    """``snncc compile braille_noDelay_noBias_subtract.nir --dt 1e-4 --reset subtract --rule single
    --calibration-samples 4 -o good.xylo`` and ``in12.npy``, (2, 256, 12) spikes, in one folder."""
    from snncc.cli.main import run

    d = tmp_path_factory.mktemp("hostile")
    assert run(["compile", str(NIR), *MODEL, "--rule", "single", "--calibration-samples", "4", "-o",
                str(d / "good.xylo")]) == 0
    np.save(d / "in12.npy", (np.random.default_rng(0).random((2, 256, 12)) < 0.08).astype(np.uint8))
    (d / "outside").mkdir()
    return d


def copy_of(good: Path, name: str) -> Path:
    out = good / name
    shutil.rmtree(out, ignore_errors=True)
    shutil.copytree(good / "good.xylo", out)
    return out


def linked(good: Path, name: str, member: str, absolute: bool) -> Path:
    """A copy whose ``member`` is a symbolic link to the same bytes outside the artefact (the hashes match)."""
    art = copy_of(good, name)
    target = good / "outside" / f"{name}-{member}"
    shutil.copyfile(art / member, target)
    (art / member).unlink()
    (art / member).symlink_to(target if absolute else Path("..") / "outside" / target.name)
    return art


def manifest_edited(good: Path, name: str, edit) -> Path:
    art = copy_of(good, name)
    manifest = json.loads((art / "manifest.json").read_text())
    edit(manifest, art)
    (art / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return art


def refused(capsys, args) -> str:
    code, _, err = run_cli([str(a) for a in args], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("snncc: error: "), (code, err)
    assert "Traceback" not in err
    return lines[0]


def names_link(line: str, art: Path, member: str) -> bool:
    """The one line names the artefact, the linked file and why (the kit's wording of the field may change:
    ``<art>/<member>: <member>: is a symbolic link`` or ``<art>: manifest.json/files/<member>: lists ...``)."""
    return line.startswith(f"snncc: error: {art}") and member in line and "symbolic link" in line


def commands(good: Path, art: Path, *verbs: str) -> dict[str, list]:
    every = {"emulate": ["emulate", art, "--input", good / "in12.npy", "-o", good / f"{art.name}.npz"],
             "map": ["map", art], "report": ["report", art, "--energy"],
             "check": ["check", NIR, *MODEL, "--artefact", art, "--samples", "20"]}
    return {v: every[v] for v in verbs}


@pytest.mark.parametrize("absolute", [False, True], ids=["relative", "absolute"])
def test_spec_npz_linked_outside_is_refused_by_every_reader(good, capsys, absolute):
    art = linked(good, f"spec_{absolute}.xylo", "spec.npz", absolute)
    for verb, args in commands(good, art, "emulate", "map", "report", "check").items():
        line = refused(capsys, args)
        assert names_link(line, art, "spec.npz"), (verb, line)


@pytest.mark.parametrize("absolute", [False, True], ids=["relative", "absolute"])
def test_manifest_linked_outside_is_refused(good, capsys, absolute):
    """The manifest is never read through the link: with --target xylo (and by check --artefact) the line names
    it; without, no target recognises the directory and the default reader says so in one line."""
    art = linked(good, f"manifest_{absolute}.xylo", "manifest.json", absolute)
    for verb, args in commands(good, art, "emulate", "map").items():
        line = refused(capsys, [*args, "--target", "xylo"])
        assert names_link(line, art, "manifest.json"), (verb, line)
        refused(capsys, args)
    line = refused(capsys, commands(good, art, "check")["check"])
    assert names_link(line, art, "manifest.json"), line


@pytest.mark.parametrize("member", ["README.md", "run_on_board.py"])
def test_readme_or_board_script_linked_outside_is_not_hashed_through_the_link(good, capsys, member):
    art = linked(good, f"{member}.xylo", member, absolute=True)
    for verb, args in commands(good, art, "check", "emulate").items():
        line = refused(capsys, args)
        assert names_link(line, art, member), (verb, line)


@pytest.mark.parametrize("field, value, rule", [
    ("input_pad", -5, "must be a whole number from 0 to"), ("output_lag", "abc", "must be a whole number from 0 to"),
    ("output_lag", float("nan"), "must be a whole number from 0 to"), ("output_lag", 1.5, "got 1.5"),
], ids=["pad-negative", "lag-text", "lag-nan", "lag-fraction"])
def test_a_bad_feed_is_refused(good, capsys, field, value, rule):
    art = manifest_edited(good, f"feed_{field}_{value}.xylo", lambda m, _: m["feed"].__setitem__(field, value))
    for verb, args in commands(good, art, "emulate", "map", "check").items():
        line = refused(capsys, args)
        assert f"{art}/manifest.json: feed.{field}: " in line and rule in line, (verb, line)


def test_an_unknown_chip_key_is_refused_by_emulate_and_map(good, capsys):
    art = manifest_edited(good, "chip.xylo", lambda m, _: m["chip"].__setitem__("key", "syns99999"))
    for verb, args in commands(good, art, "emulate", "map").items():
        line = refused(capsys, args)
        assert f"{art}/manifest.json: chip.key: must be one of syns61201, syns63300, syns65302" in line, (verb, line)


def test_a_spec_beyond_its_chips_alias_limit_is_not_emulated_but_mapped(good, capsys):
    def two_aliases(manifest, art):
        arrays = dict(np.load(art / "spec.npz", allow_pickle=False))
        table = np.full((arrays["threshold"].size, 2), -1, np.int32)
        table[0] = [1, 2]
        arrays["aliases"] = table
        (art / "spec.npz").write_bytes(npz_bytes(arrays))
        manifest["files"]["spec.npz"] = hashlib.sha256((art / "spec.npz").read_bytes()).hexdigest()

    art = manifest_edited(good, "alias.xylo", two_aliases)
    for verb, args in commands(good, art, "emulate", "report").items():
        line = refused(capsys, args)
        assert f"{art}/spec.npz: aliases: Xylo Audio 2 (SYNS61201) allows at most 1 alias target" in line, (verb, line)
    code, out, err = run_cli(["map", art, "--json"], capsys)
    assert code == 0, err
    assert json.loads(out)["usage"]["syns61201"]["alias targets per neuron (largest)"] == \
        {"used": 2, "limit": 1, "fits": False}
