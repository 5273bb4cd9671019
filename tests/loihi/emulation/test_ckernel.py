"""The C kernel (kernel.c, built by the system's compiler) against the numba kernel and the plain statement: every
type signature, sparse and dense blocks, delays, wraps, wide and stream runs, threads; and how it is chosen, built
and cached (snncc.native), with the numba kernel where no compiler builds it."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import snncc.native as native
from snncc.errors import SnnccError
from snncc.targets.loihi import native as loihi_native
from snncc.targets.loihi.emulation import ckernel, emulator
from snncc.targets.loihi.mapping import kernels as mapping_kernels
from snncc.targets.loihi.emulation.flat import KERNEL_SIGNATURES, kernel_name, narrowest_int
from snncc.targets.loihi.emulation.emulator import PreparedNetwork, reference_run
from tests.loihi.emulation.test_kernel import _same
from tests.loihi.emulation.test_sparse_kernel import _thin
from snncc_test_helpers import need_c_compiler
from tests.loihi.helpers import random_network

# the numba kernel (the fallback where no C compiler is found) is compared on three signatures that cover every
# accumulator, both weight kinds and both state types, on every network below, and every other numba run of these
# tests uses one of them: a cold numba compile of one signature takes 5-7 s, and CI starts with an empty numba cache
NUMBA_CHECKED = {("int16", "int8", "int32"), ("int32", "int32", "int64"), ("int64", "int64", "int64")}
NETWORKS = [(60, {}), (61, {"big": True}), (62, {"split_exponents": True, "per_synapse_delays": False}),
            (63, {"profiles": True, "recurrent": False}), (64, {"big": True, "per_synapse_delays": False})]


def _forget_built(monkeypatch):
    """As in a new process: no library loaded or looked up yet."""
    monkeypatch.setattr(native, "_loaded", {})
    monkeypatch.setattr(native, "_requested", {})
    monkeypatch.setattr(loihi_native, "_prepared", {})


def _inputs(seed, net, batch=5, steps=36, p=0.3):
    return (np.random.default_rng(seed).random((batch, steps, net.input_width)) < p).astype(np.uint8)


def _with_types(prepared, acc, w, state):
    """``prepared`` running signature (acc, w, state), or None where the network's values do not fit it
    (a wider accumulator or weight type holds the same integers, so the results must not change)."""
    flat = prepared.flat
    weights_fit_int8 = narrowest_int(int(flat.wflat.min(initial=0)), int(flat.wflat.max(initial=0))) is np.int8
    if np.iinfo(acc).bits < np.iinfo(flat.acc_dtype).bits or (w == "int8" and not weights_fit_int8):
        return None
    lay, wraps, kl, groups, proto = flat.registers(False)
    if np.dtype(proto.dtype).name == "int64" and state == "int32":
        return None
    flat.acc_dtype = np.dtype(acc).type
    flat.wflat = flat.wflat.astype(w)
    flat._registers[False] = (lay, wraps, kl, groups, np.zeros(0, state))
    return prepared


@pytest.mark.parametrize("acc, w, state", KERNEL_SIGNATURES)
def test_every_signature_of_the_c_kernel_gives_the_statements_integers_and_numbas(monkeypatch, acc, w, state):
    need_c_compiler()
    ran = 0
    for sparse in (False, True):
        if sparse:   # blocks of >= 60 entries as SparseBlocks: the hidden layer's, not the output layer's
            monkeypatch.setattr(emulator, "SPARSE_MIN_SIZE", 60)
            monkeypatch.setattr(emulator, "SPARSE_MAX_DENSITY", 1.0)
        for seed, kwargs in NETWORKS:
            net = _thin(random_network(seed, **kwargs), seed) if sparse else random_network(seed, **kwargs)
            x = _inputs(seed, net)
            for record in ("outputs", "all"):
                want = reference_run(net, x, record=record)
                for how in ("c", "numba") if (acc, w, state) in NUMBA_CHECKED else ("c",):
                    monkeypatch.setenv(ckernel.VARIABLE, how)
                    prepared = _with_types(PreparedNetwork(net), acc, w, state)
                    if prepared is None:
                        continue
                    if record == "all" and state == "int64":
                        continue    # records are int32 (run_flat refuses state beyond 32 bits for them)
                    assert kernel_name(prepared.flat) == (ckernel.C_KERNEL if how == "c" else ckernel.NUMBA_KERNEL)
                    _same(prepared.run(x, record=record, threads=2), want, record)
                    ran += 1
    assert ran >= 2, "too few networks exercised this signature"


@pytest.mark.parametrize("seed, kwargs", NETWORKS[:3])
def test_wide_and_stream_runs_of_the_c_kernel_equal_the_numba_kernels(monkeypatch, seed, kwargs):
    need_c_compiler()
    net = random_network(seed, **kwargs)
    x = _inputs(seed, net, batch=3)
    got = {}
    for how in ("c", "numba"):
        monkeypatch.setenv(ckernel.VARIABLE, how)
        prepared = PreparedNetwork(net)
        # int32 accumulator and weights, int64 state (the same integers): a numba signature of NUMBA_CHECKED
        prepared = _with_types(prepared, "int32", "int32", "int64")
        got[how] = (prepared.run(x, wide=True, threads=1), prepared.run(x, mode="stream", gap=7),
                    prepared.run(x, threads=3))
    for c_run, numba_run in zip(got["c"], got["numba"]):
        _same(c_run, numba_run, "outputs")
    assert got["c"][0].overflow == {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    if kwargs.get("big"):
        assert got["c"][2].overflow["q_wrap"] > 0


def test_a_built_kernel_is_cached_and_loaded_without_a_compile(tmp_path, monkeypatch):
    need_c_compiler()
    monkeypatch.setenv(ckernel.VARIABLE, "auto")
    monkeypatch.setenv("SNNCC_CACHE_DIR", str(tmp_path))
    _forget_built(monkeypatch)
    run = ckernel.compiled(np.int32, np.int8, np.int32)
    assert run is not None
    (built,) = tmp_path.glob("loihi-kernel-int32-int8-int32-*.so")
    _forget_built(monkeypatch)

    def no_compile(*args, **kwargs):
        raise AssertionError("compiled again")

    monkeypatch.setattr(subprocess, "run", no_compile)
    assert ckernel.compiled(np.int32, np.int8, np.int32) is not None       # loaded from the cache
    monkeypatch.undo()
    # a damaged file is built again (in a fresh interpreter: this one has the library mapped, and the dynamic
    # loader would hand back that copy by its name); a new file, not the mapped one overwritten
    built.unlink()
    built.write_bytes(b"not a shared library")
    probe = ("import numpy as np\nfrom snncc.targets.loihi.emulation import ckernel\n"
             "assert ckernel.compiled(np.int32, np.int8, np.int32) is not None\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300,
                          env={**os.environ, "SNNCC_CACHE_DIR": str(tmp_path), "SNNCC_LOIHI_KERNEL": "auto"})
    assert done.returncode == 0, done.stderr
    assert built.read_bytes()[:4] == b"\x7fELF"
    assert not list(tmp_path.glob(".*.tmp"))                                # no temporary file is left
    built.chmod(0o777)              # a file others may write is never loaded (nor replaced: it is not rebuilt)
    _forget_built(monkeypatch)
    monkeypatch.setenv(ckernel.VARIABLE, "auto")
    monkeypatch.setenv("SNNCC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(native, "_build", lambda *args: None)
    assert ckernel.compiled(np.int32, np.int8, np.int32) is None


def test_without_a_working_compiler_auto_runs_the_numba_kernel_and_c_is_refused(tmp_path, monkeypatch):
    net = random_network(65)
    x = _inputs(65, net, batch=2)
    want = reference_run(net, x)
    monkeypatch.setenv("SNNCC_CACHE_DIR", str(tmp_path))
    for broken in ("false", str(tmp_path / "no-such-compiler")):
        _forget_built(monkeypatch)
        monkeypatch.setattr(native, "compiler", lambda: native.shutil.which(broken))   # a failing build, or none
        prepared = _with_types(PreparedNetwork(net), "int32", "int32", "int64")   # a NUMBA_CHECKED signature
        monkeypatch.setenv(ckernel.VARIABLE, "auto")
        assert kernel_name(prepared.flat) == ckernel.NUMBA_KERNEL
        _same(prepared.run(x), want, "outputs")
        monkeypatch.setenv(ckernel.VARIABLE, "c")
        with pytest.raises(SnnccError, match="SNNCC_LOIHI_KERNEL: the C kernel could not be built"):
            prepared.run(x)
    assert not list(tmp_path.iterdir())


def test_an_unknown_kernel_choice_is_one_error_line(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv(ckernel.VARIABLE, "fortran")
    with pytest.raises(SnnccError, match="SNNCC_LOIHI_KERNEL: must be one of auto, c, numba"):
        PreparedNetwork(random_network(66)).run(_inputs(66, random_network(66), batch=1))
    # the command: one line, exit 2, no output file; the bundle and the inputs untouched
    from snncc.targets.loihi.bundle.write import write_bundle
    from snncc_test_helpers import run_cli

    net = random_network(66)
    bundle, inputs, out = tmp_path / "n.net", tmp_path / "x.npy", tmp_path / "o.npz"
    write_bundle(net, bundle)
    np.save(inputs, _inputs(66, net, batch=2))
    before = {p: p.read_bytes() for p in (bundle, inputs)}
    code, _, err = run_cli(["emulate", bundle, "--input", inputs, "-o", out], capsys)
    assert code == 2 and err.strip().count("\n") == 0, err
    assert err.startswith("snncc: error: ") and "SNNCC_LOIHI_KERNEL: must be one of auto, c, numba" in err
    assert not out.exists() and {p: p.read_bytes() for p in before} == before


@pytest.mark.parametrize("source, defines", [
    (ckernel.SOURCE, {"ACC_T": "int16_t", "W_T": "int8_t", "STATE_T": "int32_t", "DECAY_SHIFT": "12"}),
    (ckernel.SOURCE, {"ACC_T": "int64_t", "W_T": "int64_t", "STATE_T": "int64_t", "DECAY_SHIFT": "12"}),
    (mapping_kernels.SOURCE, {}),
])
def test_the_c_sources_compile_without_a_warning(tmp_path, source, defines):
    need_c_compiler()
    cc = native.compiler()
    flags = [*native.FLAGS, "-Wall", "-Wextra", "-Werror", *(f"-D{k}={v}" for k, v in defines.items())]
    done = subprocess.run([cc, *flags, "-o", str(tmp_path / "k.so"), str(source)], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr


def test_a_cache_that_cannot_be_written_builds_nothing_and_the_numba_kernel_runs(tmp_path, monkeypatch):
    net = random_network(67)
    x = _inputs(67, net, batch=2)
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    monkeypatch.setenv(ckernel.VARIABLE, "auto")
    for cache, writable in ((blocker / "cache", True), (tmp_path / "read-only", False)):
        monkeypatch.setenv("SNNCC_CACHE_DIR", str(cache))      # under a file: not even a directory can be made
        monkeypatch.setattr(native.os, "access", lambda path, mode, ok=writable: ok)   # (root writes anywhere)
        _forget_built(monkeypatch)
        prepared = _with_types(PreparedNetwork(net), "int32", "int32", "int64")   # a NUMBA_CHECKED signature
        assert ckernel.compiled(np.int16, np.int8, np.int32) is None
        assert kernel_name(prepared.flat) == ckernel.NUMBA_KERNEL
        _same(prepared.run(x), reference_run(net, x), "outputs")
    assert not (tmp_path / "read-only").exists() or not list((tmp_path / "read-only").iterdir())
