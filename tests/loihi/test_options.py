"""Loihi's options (``targets/loihi/options.py``): one record, validated once, reaching the lowering, the checks
and fine-tuning as the record; its constants defined once; the entry module light."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from snncc.errors import SnnccError
from snncc.targets.base import declared_options
from snncc.targets.loihi import options
from snncc.targets.loihi.options import LoihiOptions, LoihiStudyKnobs
from tests.loihi.helpers import small_graph


def test_the_lowering_reads_the_constants_the_options_declare():
    """Moved from tests/targets/test_registry.py: the choices the command line offers are the lowering's, now by
    identity (one definition, no copies)."""
    from snncc.targets.loihi.lowering import lower, quantize, replicate, timing

    assert timing.TIMINGS is options.TIMINGS and quantize.SCALE_RULES is options.SCALE_RULES
    assert replicate.MAX_REPLICAS is options.MAX_REPLICAS and lower.COMPILE_OPTIONS is options.COMPILE_OPTIONS
    declared = declared_options(LoihiOptions)
    assert declared["timing"].choices == options.TIMINGS and declared["scale"].choices == options.SCALE_RULES
    assert declared["replicas"].maximum == options.MAX_REPLICAS


def test_the_entry_and_options_modules_import_nothing_heavy():
    code = ("import sys, json\nimport snncc.targets.loihi.capabilities, snncc.targets.loihi.options\n"
            "print(json.dumps(sorted(m for m in ('numpy', 'torch', 'numba', 'h5py', 'scipy') if m in sys.modules)))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout) == []


def test_the_validated_record_reaches_the_lowering_as_it_is(monkeypatch):
    from snncc.targets.loihi import target
    from snncc.targets.loihi.lowering import lower

    seen = []
    real = lower.lower_artefact

    def spy(graph, opts, progress=None):
        seen.append(opts)
        return real(graph, opts, progress)

    monkeypatch.setattr(lower, "lower_artefact", spy)
    target.lower(small_graph(seed=1), {"scale": "global", "time_steps": 20})
    (opts,) = seen
    assert isinstance(opts, LoihiOptions) and opts.scale == "global" and opts.time_steps == 20
    record = LoihiOptions(scale="per-layer")
    target.lower(small_graph(seed=1), record)
    assert seen[-1] is record                       # a record is passed on, never rebuilt from a dict


def test_recorded_options_are_validated_as_a_users():
    assert options.recorded({"scale": "fine", "timing": "paper", "allow_reset_change": None, "extra": 1}) == \
        LoihiOptions(scale="fine", timing="paper")
    with pytest.raises(SnnccError, match="scale must be one of"):
        options.recorded({"scale": "bogus"})
    assert LoihiOptions().compile_record() == {k: None if k != "allow_reset_change" else False
                                               for k in options.COMPILE_OPTIONS}


def test_study_knobs_are_a_second_record_never_an_option():
    assert LoihiStudyKnobs().learn == options.LEARNED and LoihiStudyKnobs().search
    assert not set(f for f in LoihiStudyKnobs.__dataclass_fields__) & set(declared_options(LoihiOptions))
