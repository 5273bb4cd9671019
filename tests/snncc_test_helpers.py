"""Helpers shared by tests: the th1 parameters file text, a CLI runner, the authors' SpyTorch loop."""

from __future__ import annotations

TH1_PARAMS = ("scale 5\ntime_bin_size 5\nnb_input_copies 2\ntau_mem 0.06\ntau_ratio 10\n"
              "fwd_weight_scale 1\nweight_scale_factor 0.01\nreg_spikes 0.004\nreg_neurons 1e-6\n")


def require(module: str):
    """``module`` imported; a test that needs it is skipped where it is missing, but fails in CI (``CI=true``),
    which installs every test extra: there a missing module is a broken install, never a reason to skip."""
    import importlib
    import os

    import pytest

    try:
        return importlib.import_module(module)
    except ImportError as ex:
        if os.environ.get("CI") == "true":
            raise
        pytest.skip(f"{module} is not installed ({ex})")


def need_c_compiler() -> None:
    """Skip a test of snncc's C kernels where no C compiler is found (the numba kernels run there), but fail in CI
    (``CI=true``), whose .ci/run installs gcc."""
    import os

    import pytest

    from snncc.native import compiler

    if compiler() is None:
        if os.environ.get("CI") == "true":
            pytest.fail("no C compiler found; CI must install gcc (.ci/run)")
        pytest.skip("no C compiler found (cc, gcc, $CC or $SNNCC_CC): the numba kernels run instead")


PROGRESS = "snncc: progress: "


def without_progress(err: str) -> str:
    """``err`` without the progress lines a command prints outside a terminal (``snncc.cli.output``)."""
    return "".join(line for line in err.splitlines(keepends=True) if not line.startswith(PROGRESS))


def run_cli(args: list[str], capsys, progress: bool = False) -> tuple[int, str, str]:
    """Run ``snncc args``; return (exit status, stdout, stderr); stderr without its progress lines unless
    ``progress`` (they are checked on their own: tests/cli/test_progress_lines.py)."""
    from snncc.cli.main import run

    code = run([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err if progress else without_progress(out.err)


def heaviside(v):
    return (v > 0).to(v.dtype)


def authors_loop(x, w_in, w_out, v_rec, alpha, beta, spike=heaviside, detach_reset=True):
    """The paper's SpyTorch loop (their run_snn), written out step by step, independent of snncc:
    ``mem[t+1] = (beta*mem[t] + syn[t]) * (1 - S[t])``. ``spike`` maps mem - 1 to spikes (a surrogate
    for gradients). Returns (output spikes, hidden spikes), each (B, T, n)."""
    import torch

    def layer(drive, n, recurrent):
        syn = x.new_zeros(x.shape[0], n)
        mem = x.new_zeros(x.shape[0], n)
        out = x.new_zeros(x.shape[0], n)
        record = []
        for t in range(x.shape[1]):
            h = drive[:, t] + (out @ recurrent if recurrent is not None else 0.0)
            out = spike(mem - 1.0)
            rst = out.detach() if detach_reset else out
            mem, syn = (beta * mem + syn) * (1.0 - rst), alpha * syn + h
            record.append(out)
        return torch.stack(record, dim=1)

    hidden = layer(torch.einsum("btc,cd->btd", x, w_in), w_in.shape[1], v_rec)
    return layer(torch.einsum("btc,cd->btd", hidden, w_out), w_out.shape[1], None), hidden


def small_rsnn(path) -> None:
    """A small seeded RSNN checkpoint (24 channels x 2 input copies, 32 hidden, 28 outputs, dt 5 ms)."""
    import torch

    from snncc.frontends.checkpoint import save_checkpoint
    from snncc.models import SNNConfig, SpikingClassifier

    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_hidden=32, n_outputs=28))
    model.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.2)
    save_checkpoint(model, path, {"dt": 0.005, "note": "test model"})


def build_workspace(directory) -> None:
    """Small files every command can take, in ``directory``: ``br/`` (SYNTHETIC Braille, 5 x 27
    letters, threshold-1 events and raw frames), ``ev.npz`` (its events, th 1 at 5 ms), ``m.pt`` (a
    small RSNN), ``b.net`` (its Loihi bundle), ``jet/`` (its Jetson artefact, 20 steps),
    ``spikes.npy`` (2 x 20 x 48 spikes: the bundle's input) and ``x.npy`` (2 x 20 x 24: the data's
    channels, which the Jetson artefact copies itself)."""
    from pathlib import Path

    import numpy as np

    import snncc.api as api

    d = Path(directory)
    api.data_synth(out=d / "br", repetitions=5, seed=0, thresholds="1")
    api.data_encode(d / "br", out=d / "ev.npz", threshold=1, bin_ms=5)
    small_rsnn(d / "m.pt")
    api.compile(d / "m.pt", target="loihi", output=d / "b.net")
    api.compile(d / "m.pt", target="jetson", output=d / "jet", time_steps=20)
    rng = np.random.default_rng(0)
    np.save(d / "spikes.npy", (rng.random((2, 20, 48)) < 0.1).astype(np.uint8))
    np.save(d / "x.npy", (rng.random((2, 20, 24)) < 0.1).astype(np.uint8))


def load_bench(name: str):
    """The script ``bench/<name>.py`` as a module, ``name`` with its folder (``"speed/bench_compile"``,
    ``"studies/xylo_paired"``): benches are scripts, not a package."""
    import importlib.util
    import sys
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "bench" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod
