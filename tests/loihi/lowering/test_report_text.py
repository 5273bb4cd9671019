"""The compile report's text (report_text.py), read from the artefact's summary record."""

from __future__ import annotations

import io

import numpy as np
from rich.console import Console

from snncc.targets.loihi import target
from snncc.targets.loihi.lowering.report_text import delay_text, exp_text, register_text, render_compile_report
from tests.loihi.helpers import small_graph


def test_register_values_as_text():
    assert register_text(np.int64(7)) == 7 and delay_text(3) == 3 and exp_text(-2) == -2
    assert register_text(np.array([3, 5, 5])) == "per-neuron 3..5 (2 values)"
    assert delay_text(np.array([[0, 4], [2, 1]])) == "per-synapse 0..4"
    assert exp_text(np.array([[0, 1], [1, 1]])) == "per-synapse 0 (1), 1 (3)"


def test_compile_report_counts_the_cores_of_the_recorded_map():
    art = target.lower(small_graph(seed=1), {"scale": "global"})
    s = art.summary()
    s["core_map"] = {**s["core_map"], "cores": s["core_map"]["cores"] * 3}   # the text reads the map's cores
    buf = io.StringIO()
    render_compile_report(s, Console(file=buf, width=200, highlight=False, color_system=None))
    text = buf.getvalue()
    assert "core map: 3 cores\n" in text and text.startswith("Loihi bundle: tSample 40")
    buf = io.StringIO()
    art.render_text(Console(file=buf, width=200, highlight=False, color_system=None))
    assert "core map: 1 cores\n" in buf.getvalue()


def test_per_neuron_registers_alone_do_not_say_lava_runs_the_bundle_differently():
    """Lava's CPU model runs per-neuron vThMant / iDecay / vDecay arrays as written (bench/studies/lava_netx_agreement.py's
    probes): the report lists them, but says netx would run the bundle differently only for a field it ignores."""
    art = target.lower(small_graph(seed=1), {"scale": "global"})
    s = art.summary()

    def text(notes):
        buf = io.StringIO()
        render_compile_report({**s, "netx_compat": notes}, Console(file=buf, width=400, highlight=False,
                                                                   color_system=None))
        return buf.getvalue()

    per_neuron = "/layer/1/neuron/{vThMant}: one value per neuron (compartment profiles; ...)"
    assert "one value per neuron" in text([per_neuron]) and "Lava would run this bundle differently" not in text(
        [per_neuron])
    assert "Lava would run this bundle differently" in text([per_neuron, "/layer/1/neuron/refDelay = 2 (...)"])


def test_compile_prints_the_exactness_verdict_and_counts_and_points_to_check(capsys):
    """No interval on the validation's 4 samples (nearly empty, and alarming): the verdict, the spike counts, and
    where agreement is measured."""
    from rich.console import Console

    art = target.lower(small_graph(seed=1), {"scale": "global"})
    art.render_text(Console(width=200, force_terminal=False))
    out = capsys.readouterr().out
    checked = next(line for line in out.splitlines() if "checked on 4 seeded random spike trains" in line)
    assert ": exact (timing True, quantized registers True, emulator kernel True)" in checked
    counts = art.validation["spike_counts"]
    assert set(counts) == {"emulator", "float"} and set(counts["float"]) == {"hidden", "out"}
    assert f"hidden {counts['emulator']['hidden']:,} vs {counts['float']['hidden']:,}" in out
    assert "`snncc check MODEL --artefact BUNDLE`" in out and "predictions" not in out and "[0." not in out
