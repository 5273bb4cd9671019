"""Compile time of the paper's th1 RSNN for Loihi (load, quantize, map, validate, write), after import.

    python bench/speed/bench_compile.py [--repeats 3] [--out bench/speed/results/compile.json]

The weights are a SYNTHETIC weight list of the authors' shape (48 -> 450 recurrent -> 28) with their
initialisation; the parameters are the paper's th1 preset. The goal: < 2 s after import.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

import torch

from snncc.frontends import LoadOptions, load_model
from snncc.targets import get_target

TH1 = ("scale 5\ntime_bin_size 5\nnb_input_copies 2\ntau_mem 0.06\ntau_ratio 10\nfwd_weight_scale 1\n"
       "weight_scale_factor 0.01\nreg_spikes 0.004\nreg_neurons 1e-6\n")


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "compile.json"))
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        g = torch.Generator().manual_seed(0)
        torch.save([torch.randn(48, 450, generator=g) / 48 ** 0.5, torch.randn(450, 28, generator=g) / 450 ** 0.5,
                    torch.randn(450, 450, generator=g) * 0.01 / 450 ** 0.5], tmp / "weights_th1.pt")
        (tmp / "parameters_th1.txt").write_text(TH1)
        loihi = get_target("loihi")
        times = []
        for i in range(args.repeats + 1):  # the first run warms numba's caches and is not counted
            t0 = time.perf_counter()
            graph = load_model(tmp / "weights_th1.pt", LoadOptions(params=tmp / "parameters_th1.txt"))
            artefact = loihi.lower(graph, {"timing": "exact", "scale": "auto"})
            artefact.write(tmp / "th1.net")
            if i:
                times.append(time.perf_counter() - t0)
    result = {
        "benchmark": "compile th1 RSNN for Loihi (load, quantize, map, validate, write)",
        "seconds_median": statistics.median(times),
        "seconds_all": times,
        "goal_seconds": 2.0,
        "meets_goal": statistics.median(times) < 2.0,
        "load_1min": os.getloadavg()[0],
        "cores": os.cpu_count(),
        "synthetic_weights": True,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
