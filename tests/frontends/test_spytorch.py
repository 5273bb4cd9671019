"""The authors' SpyTorch weight lists: the IR reproduces their training loop spike for spike."""

import io
import zipfile

import numpy as np
import pytest
import torch

from snncc.errors import SnnccError
from snncc.frontends import LoadOptions, load_model
from snncc.frontends.params import format_params, load_params, parse_params
from snncc.ir import simulate
from snncc_test_helpers import TH1_PARAMS, authors_loop



def weight_list(seed=0, n_in=48, n_h=60, n_out=28, recurrent=True):
    g = torch.Generator().manual_seed(seed)
    ws = [torch.randn(n_in, n_h, generator=g) * 3.0 / np.sqrt(n_in),
          torch.randn(n_h, n_out, generator=g) * 3.0 / np.sqrt(n_h)]
    if recurrent:
        ws.append(torch.randn(n_h, n_h, generator=g) * 0.5 / np.sqrt(n_h))
    return ws


@pytest.mark.parametrize("recurrent", [True, False])
def test_ir_equals_the_authors_loop_spike_for_spike(tmp_path, th1_params, recurrent):
    ws = weight_list(recurrent=recurrent)
    torch.save(ws, tmp_path / "weights.pt")
    g = load_model(tmp_path / "weights.pt", LoadOptions(params=th1_params))
    assert g.metadata["update_order"] == "spytorch" and g.dt == 0.005
    assert g.node("hidden").refractory == 2 and g.node("hidden").reset == "zero"
    assert [g.delay("input", "w_in"), g.delay("hidden", "w_out")] == [2, 2]
    if recurrent:
        assert g.delay("hidden", "w_rec") == 3

    rng = np.random.default_rng(3)
    x24 = (rng.random((6, 270, 24)) < 0.08).astype(np.float64)
    x = torch.as_tensor(np.tile(x24, (1, 1, 2)))  # the authors' inputs.tile((nb_input_copies,))
    alpha, beta = float(np.exp(-0.005 / 0.006)), float(np.exp(-0.005 / 0.06))
    w = [t.double() for t in ws]
    outs, hidden = authors_loop(x, w[0], w[1], w[2] if recurrent else None, alpha, beta)
    r = simulate(g, x, record="spikes")
    assert hidden.sum() > 100 and outs.sum() > 10  # the test exercises spiking, not silence
    assert np.array_equal(r.spikes["hidden"], hidden.numpy())
    assert np.array_equal(r.output, outs.numpy())
    assert np.array_equal(r.prediction, torch.argmax(outs.sum(1), dim=1).numpy())


def _retag_as_cuda(path):
    """Rewrite a torch archive so its storages claim CUDA location (as the authors' GPU saves do)."""
    src = zipfile.ZipFile(path)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename.endswith("data.pkl"):
                # pickle protocol 2: BINUNICODE 'X' + 4-byte little-endian length + text
                assert b"X\x03\x00\x00\x00cpu" in data
                data = data.replace(b"X\x03\x00\x00\x00cpu", b"X\x06\x00\x00\x00cuda:0")
            dst.writestr(item, data)
    path.write_bytes(buf.getvalue())


def test_cuda_tagged_weight_list_loads_on_the_cpu(tmp_path, th1_params):
    ws = weight_list()
    p = tmp_path / "gpu_weights.pt"
    torch.save(ws, p)
    _retag_as_cuda(p)
    with pytest.raises(Exception):  # proves the tag took: without map_location it needs CUDA
        torch.load(p, weights_only=True)
    g = load_model(p, LoadOptions(params=th1_params))
    np.testing.assert_array_equal(g.node("w_in").weight, ws[0].double().numpy().T)


def test_th1_params_rules(tmp_path):
    p = parse_params(TH1_PARAMS)
    assert p.dt == 0.005 and p.tau_syn == pytest.approx(0.006) and p.nb_input_copies == 2
    assert parse_params(format_params(p)) == p
    for text, match in [
        (TH1_PARAMS.replace("tau_ratio 10\n", ""), "tau_ratio.*missing"),
        (TH1_PARAMS + "learning_rate 3\n", "learning_rate.*unknown key"),
        (TH1_PARAMS.replace("tau_mem 0.06", "tau_mem -0.06"), "tau_mem.*positive"),
        (TH1_PARAMS.replace("tau_mem 0.06", "tau_mem fast"), "tau_mem.*not a number"),
        (TH1_PARAMS.replace("nb_input_copies 2", "nb_input_copies 2.5"), "whole number"),
        (TH1_PARAMS + "scale 3\n", "twice"),
    ]:
        f = tmp_path / "p.txt"
        f.write_text(text)
        with pytest.raises(SnnccError, match=match):
            load_params(f)


@pytest.mark.parametrize("bad, match", [
    (lambda ws: [ws[0], ws[1], ws[2][:, :10]], "V_rec.*square"),
    (lambda ws: [ws[0], ws[1].T, ws[2]], "W_out.*do not chain"),
    (lambda ws: [ws[0].clone().fill_(float("nan")), ws[1], ws[2]], "W_in.*NaN"),
])
def test_bad_weight_lists(tmp_path, th1_params, bad, match):
    torch.save(bad(weight_list()), tmp_path / "w.pt")
    with pytest.raises(SnnccError, match=match):
        load_model(tmp_path / "w.pt", LoadOptions(params=th1_params))


def test_weight_list_without_params_says_how(tmp_path):
    torch.save(weight_list(), tmp_path / "w.pt")
    with pytest.raises(SnnccError, match=r"pass params=.parameters_thN\.txt."):
        load_model(tmp_path / "w.pt")
