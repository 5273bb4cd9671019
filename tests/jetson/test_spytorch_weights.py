"""The authors' weight list + parameters file compiles to a Jetson artefact whose predictions equal
their float model run in THEIR update order (the loop below is written from their code's
equations, independently of snncc's IR)."""

from __future__ import annotations

import math

import numpy as np
import torch

from snncc.targets.jetson.standalone_runner import ArtefactRunner
from snncc_test_helpers import TH1_PARAMS, run_cli

STEPS = 40


def authors_lif_layer(h_in: torch.Tensor, alpha: float, beta: float, v_rec: torch.Tensor | None) -> torch.Tensor:
    """Their loop: h = h_in[t] + S_prev @ V; S = (mem - 1 > 0); new_syn = alpha*syn + h;
    new_mem = (beta*mem + syn) * (1 - S); record S."""
    batch, steps, n = h_in.shape
    syn = torch.zeros(batch, n)
    mem = torch.zeros(batch, n)
    out = torch.zeros(batch, n)
    spikes = []
    for t in range(steps):
        h = h_in[:, t]
        if v_rec is not None:
            h = h + out @ v_rec
        out = (mem - 1.0 > 0).float()
        new_syn = alpha * syn + h
        new_mem = (beta * mem + syn) * (1.0 - out)
        spikes.append(out)
        mem, syn = new_mem, new_syn
    return torch.stack(spikes, dim=1)


def authors_counts(weights: list[torch.Tensor], x: np.ndarray, copies: int, alpha: float, beta: float) -> np.ndarray:
    w_in, w_out, v_rec = weights
    inputs = torch.as_tensor(x).tile((copies,))                     # their inputs.tile((nb_input_copies,))
    hidden = authors_lif_layer(inputs @ w_in, alpha, beta, v_rec)    # (in, out) orientation: x @ W
    output = authors_lif_layer(hidden @ w_out, alpha, beta, None)    # readout: the same LIF
    return output.sum(dim=1).numpy()


def test_weight_list_compiles_to_artefact_matching_their_float_model(tmp_path, capsys):
    g = torch.Generator().manual_seed(5)
    weights = [torch.randn(12, 20, generator=g) * 1.2, torch.randn(20, 5, generator=g) * 1.5,
               torch.randn(20, 20, generator=g) * 0.4]
    wpath, ppath = tmp_path / "weights.pt", tmp_path / "parameters_th1.txt"
    torch.save(weights, wpath)
    ppath.write_text(TH1_PARAMS)  # nb_input_copies 2, tau_mem 0.06 s, tau_ratio 10, 5 ms bins
    out = tmp_path / "jetson"
    code, _, err = run_cli(["compile", wpath, "--params", ppath, "--target", "jetson", "-o", out,
                            "--time-steps", STEPS], capsys)
    assert code == 0, err
    x = (np.random.default_rng(17).random((16, STEPS, 6)) < 0.25).astype(np.float32)
    dt, tau_mem = 0.005, 0.06
    alpha, beta = math.exp(-dt / (tau_mem / 10)), math.exp(-dt / tau_mem)
    counts = authors_counts(weights, x, 2, alpha, beta)
    theirs = np.argmax(counts, axis=1)  # prediction: argmax of summed output spikes
    runner = ArtefactRunner(str(out), backend="onnxruntime")
    ours = runner.run(x)
    assert ours["counts"].sum() > 0, "the test network must produce output spikes"
    assert len(set(theirs.tolist())) > 1, "predictions should not all be one class"
    np.testing.assert_array_equal(ours["prediction"], theirs)
    np.testing.assert_array_equal(ours["counts"], counts)
    np.testing.assert_array_equal(runner.stream(x)["prediction"], theirs)
