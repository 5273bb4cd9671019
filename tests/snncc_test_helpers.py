"""Helpers shared by tests: the th1 parameters file text and a CLI runner."""

from __future__ import annotations

TH1_PARAMS = ("scale 5\ntime_bin_size 5\nnb_input_copies 2\ntau_mem 0.06\ntau_ratio 10\n"
              "fwd_weight_scale 1\nweight_scale_factor 0.01\nreg_spikes 0.004\nreg_neurons 1e-6\n")


def run_cli(args: list[str], capsys) -> tuple[int, str, str]:
    """Run ``snncc args``; return (exit status, stdout, stderr)."""
    from snncc.cli.main import run

    code = run([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err
