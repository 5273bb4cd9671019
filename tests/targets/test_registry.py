"""The registry and the option declarations: listing or choosing a target imports nothing heavy, a
declaration is validated by the target that made it, shared flags are offered once, and options that
belong to a capability are declared once and refused where they do not apply."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass

import pytest

from snncc.errors import SnnccError
from snncc.targets import (
    AgreementOptions, available_targets, get_target, offered_options, offering, target_options, verb_options,
)
from snncc.targets.base import (
    Option, OptionRecord, TargetOptions, capability_options, declared_options, option,
)

from snncc_test_helpers import run_cli

HEAVY = ("torch", "onnx", "onnxruntime", "numba")


def test_choosing_every_target_imports_no_heavy_library():
    """A fresh interpreter lists the targets, chooses each and reads its declarations and flags."""
    code = ("import sys, json\n"
            "from snncc.targets import available_targets, get_target, offered_options\n"
            "names = available_targets()\n"
            "for n in names:\n"
            "    t = get_target(n); t.options_type\n"
            "offered_options(['lower', 'check', 'agree', 'map'])\n"
            f"print(json.dumps([names, sorted(m for m in {list(HEAVY)!r} if m in sys.modules)]))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    names, heavy = json.loads(proc.stdout)
    assert {"ir", "loihi", "jetson"} <= set(names) and heavy == []


def test_the_check_can_fail():
    """The same probe sees torch once a module that imports it is loaded."""
    code = "import sys\nimport snncc.models.snn\nprint('torch' in sys.modules)\n"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.stdout.strip() == "True", proc.stderr


# -- declarations ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Demo(TargetOptions):
    gain: float | None = option("Gain.", above=0, maximum=4)
    mode: str | None = option("Mode.", choices=("a", "b"))
    steps: int | None = option("Steps.", minimum=1, capabilities=("lower",))
    fast: bool = option("Fast.", default=False)
    seed: int = 0                                            # a setting, not an option


class DemoTarget:
    name = "demo"
    options_type = Demo


def test_declarations_give_name_flag_kind_default_and_capabilities():
    d = declared_options(Demo)
    assert list(d) == ["gain", "mode", "steps", "fast"]
    assert [(o.flag, o.kind, o.switch) for o in d.values()] == [
        ("--gain", float, False), ("--mode", str, False), ("--steps", int, False), ("--fast", bool, True)]
    assert d["fast"].default is False and d["steps"].capabilities == ("lower",)
    with pytest.raises(TypeError):
        @dataclass(frozen=True)
        class Bad(OptionRecord):
            size: list | None = option("A list.")

        declared_options(Bad)


@pytest.mark.parametrize("given, expected", [
    ({"gain": 2, "mode": "b", "steps": "7", "fast": True}, Demo(gain=2.0, mode="b", steps=7, fast=True)),
    ({"steps": 3.0, "gain": None, "fast": False}, Demo(steps=3)),
    ({"seed": 5}, Demo(seed=5)),
])
def test_a_target_builds_its_record_from_given_values(given, expected):
    from snncc.targets.base import target_options as build

    assert build(DemoTarget(), given) == expected


@pytest.mark.parametrize("given, line", [
    ({"gain": 0}, "--gain: must be a number > 0 and <= 4, got 0"),
    ({"gain": "x"}, "--gain: must be a number > 0 and <= 4, got 'x'"),
    ({"gain": True}, "--gain: must be a number > 0 and <= 4, got True"),
    ({"mode": "c"}, "--mode: must be one of a, b, got 'c'"),
    ({"steps": 2.5}, "--steps: must be a whole number >= 1, got 2.5"),
    ({"steps": 0}, "--steps: must be a whole number >= 1, got 0"),
    ({"fast": "yes"}, "--fast: must be true or false, got 'yes'"),
    ({"colour": "red"}, "--colour: does not apply to --target demo (it takes --gain, --mode, --steps, --fast)"),
])
def test_a_value_outside_the_declaration_is_refused_in_one_line(given, line):
    from snncc.targets.base import target_options as build

    with pytest.raises(SnnccError) as err:
        build(DemoTarget(), given)
    assert err.value.line() == line


def test_an_option_of_another_verb_is_refused_naming_the_verb():
    from snncc.targets.base import target_options as build

    with pytest.raises(SnnccError) as err:
        build(DemoTarget(), {"steps": 4}, "check")
    assert err.value.line() == "--steps: does not apply to check with labelled data (--target demo takes it for compile)"
    with pytest.raises(SnnccError) as err:
        build(DemoTarget(), {"colour": "red"}, "check")
    assert err.value.line() == "--colour: does not apply to --target demo (it takes --gain, --mode, --fast)"
    assert build(DemoTarget(), {"steps": None}, "check") == Demo()


def test_loihi_takes_stream_for_check_only():
    loihi = get_target("loihi")
    with pytest.raises(SnnccError) as err:
        target_options(loihi, {"stream": True}, "lower")
    assert err.value.line() == "--stream: does not apply to compile (--target loihi takes it for check with labelled data)"
    with pytest.raises(TypeError):             # no installed target takes stream for compile: api.compile(stream=...)
        verb_options(loihi, {"stream": True}, "lower")


def test_capability_options_are_declared_once_and_refused_where_they_do_not_apply():
    assert capability_options(AgreementOptions, {"density": "0.2", "samples": None}) == AgreementOptions(density=0.2)
    with pytest.raises(SnnccError) as err:
        capability_options(AgreementOptions, {"density": 1.5})
    assert err.value.line() == "--density: spike density must be in (0, 1], got 1.5"
    loihi = get_target("loihi")
    split = verb_options(loihi, {"density": 0.2, "scale": "global", "stream": False}, "agree", ("check", "agree"))
    assert split.of(AgreementOptions) == AgreementOptions(density=0.2) and split.target.scale == "global"
    with pytest.raises(SnnccError) as err:
        verb_options(loihi, {"noise": 0.1}, "check", ("check", "agree"))
    assert err.value.line() == "--noise: applies only to check without labels (agreement), not to check with labelled data"
    offers = {o.name: o for o in offered_options(["check", "agree"])}
    assert offers["density"].targets == tuple(offering("agree")) == ("c", "jetson", "loihi", "xylo")   # all measure agreement
    assert offers["density"].default == 0.08 and "(default 0.08)" in offers["density"].help


def test_shared_flags_are_offered_once_and_a_switch_value_clash_is_refused(monkeypatch):
    import snncc.targets as registry

    @dataclass(frozen=True)
    class Other(TargetOptions):
        gain: str | None = option("Gain as text.")
        fast: int | None = option("Fast as a number.", capabilities=("check",))

    class OtherTarget:
        name = "other"
        options_type = Other

    monkeypatch.setattr(registry, "loaded_targets", lambda: [DemoTarget(), OtherTarget()])
    offers = {o.name: o for o in offered_options(["lower"]) if o.name == "gain"}
    assert offers["gain"].kind is str and offers["gain"].targets == ("demo", "other")   # each target converts
    assert offers["gain"].help == "--target demo: Gain; --target other: Gain as text"
    with pytest.raises(SnnccError) as err:
        registry.offered_options(["check"])
    assert err.value.line() == ("--fast: targets declare it both as a switch and as a value: demo (switch), "
                                "other (value)")


def test_registered_targets():
    assert {"ir", "jetson", "loihi"} <= set(available_targets())
    assert offering("lower")[:3] and "jetson" in offering("bench") and "loihi" in offering("hardware")


# -- the verbs, through the CLI -------------------------------------------------------------------------
def test_check_refuses_agreement_options_with_labelled_data(small_rsnn_checkpoint, tmp_path, capsys):
    import numpy as np

    data = tmp_path / "d.npz"
    np.savez(data, inputs=np.zeros((2, 30, 48), np.uint8), labels=np.array([0, 1]))
    code, stdout, err = run_cli(["check", small_rsnn_checkpoint, "--data", data, "--density", "0.2"], capsys)
    assert (code, stdout) == (2, "")
    assert err == ("snncc: error: snncc check: --density: applies only to check without labels (agreement), not "
                   "to check with labelled data\n")
    code, _, err = run_cli(["check", small_rsnn_checkpoint, "--samples", "3", "--limit", "3"], capsys)
    assert code == 2 and err == "snncc: error: snncc check: --samples: give --samples or --limit, not both\n"
    code, _, err = run_cli(["compile", small_rsnn_checkpoint, "-t", "loihi", "-o", tmp_path / "m.net", "--scale", "x"],
                           capsys)
    assert code == 2 and err == ("snncc: error: snncc compile: --scale: scale must be one of global, per-layer, split, "
                                 "fine, auto\n")


def test_a_verb_calling_two_capabilities_takes_the_options_of_both():
    """(compile with fine-tuning will call lower and the fine-tuning capability: one call splits both.)"""
    loihi = get_target("loihi")
    both = verb_options(loihi, {"time_steps": 50, "density": 0.3}, ("lower", "agree"))
    assert both.target.time_steps == 50 and both.of(AgreementOptions).density == 0.3
    with pytest.raises(SnnccError) as err:
        verb_options(loihi, {"stream": True}, ("lower", "agree"), ("lower", "check", "agree"))
    assert err.value.line() == "--stream: does not apply to compile (--target loihi takes it for check with labelled data)"
