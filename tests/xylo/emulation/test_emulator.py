"""The Xylo emulator's own rules and interface (its agreement with xylosim: test_emulator_oracle.py)."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.errors import SnnccError
from snncc.targets.xylo.spec import XyloSpec
from snncc.targets.xylo.emulation import kernel as _kernel
from snncc.targets.xylo.emulation import vectorized
from snncc.targets.xylo.chip import CORE
from snncc.targets.xylo.emulation.emulator import (
    STATE_NAMES, XyloResult, check_inputs, decay, effective_weights, emulate, reference_run, wrap16, wrapped_weights,
)
from tests.xylo.networks import Knobs, random_inputs, random_spec


KNOBS = dict(seed=3, n_in=4, n_hidden=12, n_out=3, n_ien=8, n_oen=5, synapse_axis=2, shift_in=7, shift_rec=5,
             shift_out=6, density=0.5, threshold_scale=0.5, bias_fraction=0.5, alias_fraction=0.0,
             negative_thresholds=False)


def spec_for_tests(**changes):
    k = dict(KNOBS, alias_fraction=0.3)
    k.update(changes)
    return random_spec(Knobs(**k))


def test_decay_is_an_arithmetic_shift_or_the_sign():
    x = np.array([-32768, -5, -1, 0, 1, 5, 32767, 100])
    dash = np.array([0, 1, 15, 3, 4, 1, 15, 2])
    assert decay(x, dash).tolist() == [-32768, -3, -1, 0, 1, 2, 1, 25]


def test_effective_weights_wrap_and_report_the_wrapped_ones():
    spec = spec_for_tests(shift_in=9, shift_rec=0, shift_out=15)
    w_in, w_rec, w_out = effective_weights(spec)
    raw = spec.weights_in.astype(np.int64) << 9
    assert np.array_equal(w_in[:, :, :2], ((raw + 32768) & 0xFFFF) - 32768)
    assert np.array_equal(w_rec, np.asarray(spec.weights_rec, np.int64))
    assert set(np.unique(w_out)) <= {-32768, 0}          # odd w << 15 is -32768, even ones 0
    wrapped_in, wrapped_rec, _ = wrapped_weights(spec)
    assert wrapped_in.any() and not wrapped_rec.any()
    assert np.array_equal(wrap16(np.array([32768, -32769, 65535])), [-32768, 32767, -1])


def test_the_compiled_quotient_is_exact_for_every_v_at_many_thresholds():
    """_quotient(v, th, 1/th) == v // th (checked once for all int16 v x all thresholds 1..32767,
    here for all v at a spread of thresholds)."""
    from numba import njit

    @njit
    def mismatches(thresholds):
        bad = 0
        for th in thresholds:
            t = np.float32(th)
            inv = np.float32(1) / t
            for v in range(-32768, 32768):
                if _kernel._quotient(np.float32(v), t, inv) != np.float32(v // th):
                    bad += 1
        return bad

    rng = np.random.default_rng(0)
    thresholds = np.concatenate([np.arange(1, 300), [511, 512, 513, 4095, 4096, 16383, 16384, 32766, 32767],
                                 rng.integers(1, 32768, 200)]).astype(np.int64)
    assert mismatches(thresholds) == 0


@pytest.mark.parametrize("bad,match", [
    (np.full((1, 3, 4), -1), ">= 0"),
    (np.full((1, 3, 4), 0.5), "whole event counts"),
    (np.zeros((1, 3, 5)), "has 5 channels"),
    (np.zeros((0, 3, 4)), "batch is empty"),
    (np.zeros(4), r"shape \(T, C\) or \(B, T, C\)"),
    (np.full((1, 3, 4), np.nan), "NaN"),
])
def test_bad_inputs_are_refused_in_one_line(bad, match):
    with pytest.raises(SnnccError, match=match) as info:
        emulate(spec_for_tests(), bad)
    assert "\n" not in str(info.value)


def test_inputs_of_any_count_type_are_clipped_to_15():
    x = np.array([[[0, 1, 15, 16], [200, 3, 0, 40]]])
    assert check_inputs(x, 4).tolist() == [[[0, 1, 15, 15], [15, 3, 0, 15]]]
    assert check_inputs(x.astype(float), 4).dtype == np.uint8
    assert check_inputs(x > 0, 4).max() == 1
    assert check_inputs(x[0], 4).shape == (1, 2, 4)


def test_results_shapes_types_and_recording():
    spec = spec_for_tests()
    x = random_inputs(1, 3, 25, spec.n_in, 0.3, 20)
    plain = emulate(spec, x)
    assert isinstance(plain, XyloResult) and not plain.recorded and set(plain.arrays()) == {"output_spikes"}
    assert plain.output_spikes.shape == (3, 25, spec.n_out) and plain.output_spikes.dtype == np.uint8
    assert plain.output_spikes.max() <= CORE.max_output_spikes
    rec = emulate(spec, x, record=True)
    assert np.array_equal(rec.output_spikes, plain.output_spikes)
    assert set(rec.arrays()) == {"output_spikes", *STATE_NAMES}
    for name in ("vmem", "isyn", "isyn2"):
        assert getattr(rec, name).shape == (3, 25, spec.n_hidden) and getattr(rec, name).dtype == np.int16
    assert rec.spikes.dtype == np.uint8 and rec.spikes.max() <= CORE.max_hidden_spikes
    assert rec.vmem_out.shape == rec.isyn_out.shape == (3, 25, spec.n_out)
    assert np.array_equal(rec.counts, rec.output_spikes.sum(axis=1))


def test_samples_are_independent_and_start_from_zero_state():
    spec = spec_for_tests()
    x = random_inputs(2, 5, 30, spec.n_in, 0.3, 20)
    batch = emulate(spec, x, record=True)
    for i in range(5):
        one = emulate(spec, x[i], record=True)
        for name in ("output_spikes", *STATE_NAMES):
            assert np.array_equal(getattr(one, name)[0], getattr(batch, name)[i])
    many = np.concatenate([x] * 8)              # 40 samples: several chunks on several threads
    spread = emulate(spec, many, threads=3)
    assert np.array_equal(spread.output_spikes, np.concatenate([batch.output_spikes] * 8))


def test_dense_rows_spans_and_single_synapses_give_the_same_run(monkeypatch):
    """The kernel adds a row whole, span by span or synapse by synapse (``kernel._spans``): the same run each way,
    on a sparse random network and on a block-structured one (the copies of a replicated spec)."""
    block = spec_for_tests(n_hidden=60, density=0.1, alias_fraction=0.0)
    rec = np.zeros((120, 120, 2), np.int64)
    rec[:60, :60], rec[60:, 60:] = block.weights_rec, block.weights_rec        # two copies, side by side
    two = XyloSpec(**{**block.kwargs(), "weights_rec": rec, "aliases": [[] for _ in range(120)],
                      **{k: np.concatenate([getattr(block, k)] * 2) for k in ("dash_mem", "dash_syn", "dash_syn_2",
                                                                               "threshold", "bias")}})
    for spec in (block, two):
        xs = check_inputs(random_inputs(4, 2, 40, spec.n_in, 0.3, 20), spec.n_in)
        runs = {}
        for mode, dense_from, span_min in (("dense", 0.0, 4.0), ("spans", 2.0, 0.0), ("synapses", 2.0, 1e9)):
            monkeypatch.setattr(_kernel, "DENSE_FROM", dense_from)
            monkeypatch.setattr(_kernel, "SPAN_MIN", span_min)
            prepared = _kernel.prepare(spec)
            assert prepared.rec_spans[-1] == {"dense": _kernel.DENSE, "spans": _kernel.SPANS,
                                              "synapses": _kernel.SYNAPSES}[mode]
            runs[mode] = _kernel.run_prepared(prepared, xs, record=True)
        for name in ("output_spikes", *STATE_NAMES):
            assert np.array_equal(getattr(runs["dense"], name), getattr(runs["spans"], name)), name
            assert np.array_equal(getattr(runs["dense"], name), getattr(runs["synapses"], name)), name
        assert np.array_equal(runs["spans"].vmem, reference_run(spec, xs, record=True).vmem)


def test_recording_more_than_the_memory_cap_is_refused_before_running(monkeypatch):
    monkeypatch.setenv("SNNCC_MAX_MEMORY", str(10_000))
    spec = spec_for_tests()
    with pytest.raises(SnnccError, match="recorded states would need"):
        emulate(spec, np.zeros((20, 100, spec.n_in), np.uint8), record=True)


def test_the_package_exports_its_record_and_emulator_lazily():
    import subprocess
    import sys

    import snncc.targets.xylo as xylo

    assert xylo.emulate is emulate and xylo.XyloSpec.__name__ == "XyloSpec" and xylo.get_chip().key == "syns61201"
    with pytest.raises(AttributeError):
        xylo.lower   # noqa: B018
    code = "import sys, snncc.targets.xylo; print('snncc.targets.xylo.emulation.emulator' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_a_small_run_without_the_kernel_loaded_takes_the_vectorised_path_and_the_same_results():
    """``emulate`` of a few samples of a plain spec does not import numba (the kernel's import costs more than the
    run): the vectorised numpy path, equal to the kernel."""
    import subprocess
    import sys

    code = ("import sys, numpy as np\n"
            "from tests.xylo.networks import Knobs, random_inputs, random_spec\n"
            "from snncc.targets.xylo.emulation.emulator import emulate\n"
            f"spec = random_spec(Knobs(**{KNOBS!r}))\n"
            "x = random_inputs(3, 2, 30, spec.n_in, 0.3, 20)\n"
            "r = emulate(spec, x, record=True)\n"
            "print('numba' in sys.modules)\n"
            "np.savez(sys.argv[1], **r.arrays())\n")
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "v.npz"
        proc = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True,
                              cwd=Path(__file__).resolve().parents[3])
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip() == "False"
        spec = random_spec(Knobs(**KNOBS))
        assert vectorized.plain(spec)
        x = random_inputs(3, 2, 30, spec.n_in, 0.3, 20)
        kernel = emulate(spec, x, record=True, threads=1)
        with np.load(out) as got:
            for name, value in kernel.arrays().items():
                assert np.array_equal(got[name], value), name
