"""Helpers shared by tests: the th1 parameters file text, a CLI runner, the authors' SpyTorch loop."""

from __future__ import annotations

TH1_PARAMS = ("scale 5\ntime_bin_size 5\nnb_input_copies 2\ntau_mem 0.06\ntau_ratio 10\n"
              "fwd_weight_scale 1\nweight_scale_factor 0.01\nreg_spikes 0.004\nreg_neurons 1e-6\n")


def run_cli(args: list[str], capsys) -> tuple[int, str, str]:
    """Run ``snncc args``; return (exit status, stdout, stderr)."""
    from snncc.cli.main import run

    code = run([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


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
