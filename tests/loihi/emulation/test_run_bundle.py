"""``snncc emulate``'s batch run: where the numba kernel would run, a small run takes the numpy statement of the chip's
rules, a large one the kernel; where the C kernel builds, every run takes it. All write the same arrays (values and
dtypes), overflow counts and summary but for the implementation."""

from __future__ import annotations

import numpy as np
import pytest

from snncc.targets.loihi.emulation import run_bundle
from snncc_test_helpers import need_c_compiler
from tests.loihi.helpers import random_network


@pytest.mark.parametrize("seed, kwargs", [
    (50, {}), (51, {"per_synapse_delays": False}), (52, {"big": True}), (53, {"split_exponents": True}),
    (54, {"recurrent": False, "profiles": True}),
])
def test_the_statement_and_the_kernel_write_the_same_arrays(monkeypatch, seed, kwargs):
    need_c_compiler()
    net = random_network(seed, **kwargs)
    x = (np.random.default_rng(seed).random((5, 40, net.input_width)) < 0.3).astype(np.uint8)
    assert run_bundle.small(net, 5, 40)
    for record in ("outputs", "all"):
        monkeypatch.setenv("SNNCC_LOIHI_KERNEL", "numba")
        statement = run_bundle.emulate_bundle(net, x, record=record)
        kernels = []
        if seed == 54:     # its types are among test_ckernel.NUMBA_CHECKED (a cold numba compile per signature)
            monkeypatch.setattr(run_bundle, "STATEMENT_WORK", -1)       # every run is "large": the kernel
            kernels.append(run_bundle.emulate_bundle(net, x, record=record))
            assert kernels[-1].implementation == run_bundle.NUMBA_KERNEL
        monkeypatch.undo()
        monkeypatch.setenv("SNNCC_LOIHI_KERNEL", "c")
        kernels.append(run_bundle.emulate_bundle(net, x, record=record))   # small, but the C kernel has no start-up
        monkeypatch.undo()
        assert statement.implementation == run_bundle.STATEMENT and kernels[-1].implementation == run_bundle.C_KERNEL
        a = statement.arrays()
        for kernel in kernels:
            b = kernel.arrays()
            assert a.keys() == b.keys()
            for key in a:
                assert a[key].dtype == b[key].dtype and np.array_equal(a[key], b[key]), key
            assert {k: v for k, v in statement.summary().items() if k != "implementation"} == \
                {k: v for k, v in kernel.summary().items() if k != "implementation"}
    if kwargs.get("big"):
        assert statement.overflow["q_wrap"] > 0      # the overflow counts are compared, not only zeros


def test_long_or_heavy_runs_take_the_kernel():
    net = random_network(55)
    layers = len(net.layers) - 1
    assert run_bundle.small(net, 1, run_bundle.STATEMENT_LAYER_STEPS // layers)
    assert not run_bundle.small(net, 1, run_bundle.STATEMENT_LAYER_STEPS // layers + 1)   # per-step cost of Python
    per_step = sum(w.size * np.unique(np.asarray(d)).size for lay in net.layers[1:]
                   for w, d in ((lay.weight, lay.delay), (lay.weight_rec, lay.delay_rec)) if w is not None)
    samples = int(run_bundle.STATEMENT_WORK // (per_step * 40)) + 1
    assert not run_bundle.small(net, samples, 40) and run_bundle.small(net, samples - 1, 40)
