"""``options.py``: Xylo's option record and constants, each defined once; the lowering receives the record."""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import pytest

from snncc.targets.base import declared_options, target_options
from snncc.targets.kit import SnnccError
from snncc.targets.xylo import options
from snncc.targets.xylo.capabilities import target
from snncc.targets.xylo.chip import CHIPS

XYLO = Path(options.__file__).resolve().parent
CONSTANTS = ("CHIP_KEYS", "RULES", "MAX_REPLICAS", "RELAY_SETS", "DEFAULT_CALIBRATION_SAMPLES",
             "BOTH_CALIBRATION_SAMPLES", "DEFAULT_DENSITY", "DEFAULT_SEED", "RANDOM_STEPS", "CALIBRATION_STEPS")


def test_declared_choices_are_the_constants():
    declared = declared_options(options.XyloOptions)
    assert declared["chip"].choices == options.CHIP_KEYS == tuple(CHIPS)
    assert declared["rule"].choices == options.RULES and declared["relays"].choices == options.RELAY_SETS
    assert declared["replicas"].maximum == options.MAX_REPLICAS


def test_each_constant_is_assigned_in_options_only():
    """No module of the target copies a constant of options.py (no 'keep in sync' copies)."""
    for path in XYLO.rglob("*.py"):
        if path.name == "options.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Assign):
                names = {t.id for t in node.targets if isinstance(t, ast.Name)}
                assert not names & set(CONSTANTS), f"{path.relative_to(XYLO)} assigns {names & set(CONSTANTS)}"


def test_the_record_is_validated_by_its_declarations_and_knobs_are_a_second_record():
    opts = target_options(target, {"rule": "relayed", "replicas": 2}, "lower")
    assert isinstance(opts, options.XyloOptions) and opts.copies == 2 and opts.placement_rule == "relayed"
    assert options.XyloOptions().chip_key == "syns61201" and not options.XyloOptions().both_relays
    for bad, field in (({"rule": "fine"}, "--rule"), ({"chip": "loihi"}, "--chip"), ({"replicas": 9}, "--replicas"),
                       ({"relays": "slow"}, "--relays")):
        with pytest.raises(SnnccError) as err:
            target_options(target, bad, "lower")
        assert err.value.field == field
    knob_fields = {f.name for f in dataclasses.fields(options.XyloStudyKnobs)}
    assert knob_fields == {"calibration", "density", "emulator", "rounding", "refit", "readout"}
    assert not knob_fields & {f.name for f in dataclasses.fields(options.XyloOptions)}
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.NO_KNOBS.refit = False   # type: ignore[misc]
