"""Target-neutral measurement: the agreement rule and its interval, liveness, artefact hashes, input layouts."""

from __future__ import annotations

import hashlib
import shutil
import subprocess

import numpy as np
import pytest

from snncc.artefacts import DIRECTORY_RULE, FILE_RULE, artefact_sha256
from snncc.errors import SnnccError
from snncc.input_layout import InputLayout, to_artefact_layout
from snncc.ir import liveness
from snncc.measure.agreement import (DEFAULT_SAMPLES, LARGE_MODEL_SAMPLES, argmax_agreement, count_correlation,
                                     default_samples, wilson_interval)


def test_wilson_interval_matches_the_formula_and_its_known_values():
    lo, hi = wilson_interval(45, 50)                 # p = 0.9, n = 50: [0.7864, 0.9565] (standard tables)
    assert lo == pytest.approx(0.7864, abs=1e-4) and hi == pytest.approx(0.9565, abs=1e-4)
    assert wilson_interval(0, 10)[0] == pytest.approx(0.0, abs=1e-12) and wilson_interval(10, 10)[1] == pytest.approx(1.0)
    lo, hi = wilson_interval(500, DEFAULT_SAMPLES)   # the default count: about +-0.03 at worst
    assert 0.029 < (hi - lo) / 2 < 0.032
    with pytest.raises(ValueError):
        wilson_interval(0, 0)


def test_ties_and_silence_are_left_out_and_counted():
    ref = np.array([[3, 1, 0], [2, 2, 0], [0, 0, 0], [0, 5, 1], [1, 0, 0]])
    got = np.array([[3, 0, 0], [2, 0, 0], [0, 0, 0], [4, 0, 0], [1, 0, 0]])
    a = argmax_agreement(ref, got)
    assert (a.samples, a.decided, a.agreeing, a.ties, a.silent) == (5, 3, 2, 1, 1)
    assert a.share == pytest.approx(2 / 3) and a.low < a.share < a.high
    assert "1 tied" in a.text() and "1 silent" in a.text()


def test_agreement_over_silent_outputs_is_undefined_never_100_percent():
    silent = np.zeros((4, 7))
    a = argmax_agreement(silent, silent)
    assert a.share is None and a.low is None and not a.defined
    assert a.text().startswith("undefined: outputs silent")
    assert count_correlation(silent, silent) is None


def test_default_sample_count_is_smaller_for_large_models_only():
    assert default_samples(45, 100) == DEFAULT_SAMPLES               # a Braille RSNN
    assert default_samples(478, 270) == DEFAULT_SAMPLES              # the authors' RSNN, 450 + 28 neurons
    assert default_samples(8970, 100) == LARGE_MODEL_SAMPLES         # the Sinabs N-MNIST CNN


def test_liveness_names_silent_and_saturated_populations():
    b, t = 3, 10
    spikes = {"dead": np.zeros((b, t, 4), np.uint8), "mad": np.zeros((b, t, 2), np.uint8),
              "fine": np.zeros((b, t, 5), np.uint8)}
    spikes["mad"][:, ::2] = 1                       # every other step: every step it can with refractory 2
    spikes["fine"][0, 3, 1] = 1
    figures = liveness.activity(spikes, {"mad": 2})
    assert figures["dead"].status == "silent" and figures["mad"].status == "saturated"
    assert figures["fine"].status == "active" and figures["fine"].silent_neurons == 4
    lines = liveness.flagged(figures, "in float")
    assert len(lines) == 2 and "'dead' never spikes in float" in lines[0] and "'mad' spikes at every step" in lines[1]
    assert liveness.activity({"mad": spikes["mad"]})["mad"].status == "active"   # refractory 1: could spike every step
    tally = liveness.Tally()
    tally.add({k: v[:2] for k, v in spikes.items()})
    tally.add({k: v[2:] for k, v in spikes.items()})
    assert tally.activity({"mad": 2}) == figures


def test_a_model_silent_in_float_gets_one_warning_line_naming_the_cause():
    from snncc.ir.simulate import simulate
    from tests.loihi.helpers import small_graph

    x = (np.random.default_rng(0).random((4, 40, 8)) < 0.2).astype(np.float64)
    for graph, silent in ((small_graph(seed=1, scale=1e-4), True), (small_graph(seed=1), False)):
        res = simulate(graph, x, record="spikes")
        figures = liveness.activity(dict(res.spikes))
        line = liveness.float_silence_warning(graph, x, figures)
        if silent:
            assert "\n" not in line and "population 'hidden'" in line and "threshold or gain scale" in line
        else:
            assert line is None


def test_artefact_hashes_follow_their_stated_rules(tmp_path):
    f = tmp_path / "a.net"
    f.write_bytes(b"bundle bytes")
    assert artefact_sha256(f) == (hashlib.sha256(b"bundle bytes").hexdigest(), FILE_RULE)
    d = tmp_path / "dir"
    d.mkdir()
    for name, data in (("model.onnx", b"m"), ("manifest.json", b"{}"), ("run.py", b"r")):
        (d / name).write_bytes(data)
    (d / "model.plan").write_bytes(b"built on the board: not part of the artefact")
    names = ["manifest.json", "model.onnx", "run.py"]
    digest, rule = artefact_sha256(d, names)
    text = "".join(f"{hashlib.sha256((d / n).read_bytes()).hexdigest()}  {n}\n" for n in sorted(names))
    assert rule == DIRECTORY_RULE and digest == hashlib.sha256(text.encode()).hexdigest()
    if shutil.which("sha256sum") and shutil.which("sort"):        # the rule as the shell states it
        shell = subprocess.run(f"sha256sum {' '.join(reversed(names))} | LC_ALL=C sort -k 2 | sha256sum", shell=True,
                               cwd=d, capture_output=True, text=True, check=True)
        assert shell.stdout.split()[0] == digest
    (d / "run.py").unlink()
    with pytest.raises(SnnccError, match="run.py"):
        artefact_sha256(d, names)


def test_inputs_in_the_models_own_shape_are_made_flat_and_said():
    rng = np.random.default_rng(0)
    events = (rng.random((2, 5, 24)) < 0.3).astype(np.uint8)
    layout = InputLayout(width=48, copies=2, base=24)
    x, note = to_artefact_layout(events, layout)
    assert x.shape == (2, 5, 48) and np.array_equal(x[..., 24:], events) and "tiled the data's 24 channels 2 times" in note
    same, note = to_artefact_layout(x, layout)       # the flattened form stays accepted, nothing said
    assert same is x or np.array_equal(same, x)
    assert note is None
    frames = (rng.random((2, 5, 2, 4, 3)) < 0.3).astype(np.uint8)
    flat, note = to_artefact_layout(frames, InputLayout(width=24, frame=(2, 4, 3)))
    assert flat.shape == (2, 5, 24) and np.array_equal(flat[1, 2], frames[1, 2].reshape(-1)) and "2x4x3" in note
    odd, note = to_artefact_layout(events[..., :7], layout)     # anything else is left for the width check
    assert odd.shape[-1] == 7 and note is None
