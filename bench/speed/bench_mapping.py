"""Mapping at scale: a synthetic network of 1 million neurons and 100 million synapses.

SYNTHETIC: ``layers`` feed-forward layers of ``neurons / layers`` LIF neurons each, fed by an
input layer of the same width (the input is not counted as neurons: it occupies no core). Every
neuron has ``fan_in`` nonzero 8-bit even weights, one drawn uniformly from each of ``fan_in``
equal strata of the previous layer ("random" connectivity: the worst case for input axons) or
from a window around its own position ("local", topographic). Weights are scipy.sparse CSR.

Prints one JSON record: time to map, peak resident memory (whole process, including the network
itself), memory per synapse, cores, chips, lower bound. ``--linearity`` repeats the run at
10 %, 30 % and 100 % of the size in fresh processes to show memory growing linearly with synapses.

    python bench/speed/bench_mapping.py                       # 1M neurons, 100M synapses
    python bench/speed/bench_mapping.py --neurons 100000      # smaller
    python bench/speed/bench_mapping.py --linearity --out bench/mapping.json
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np


def synthetic_network(neurons: int, fan_in: int, layers: int, connectivity: str, seed: int):
    import scipy.sparse as sp

    from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

    rng = np.random.default_rng(seed)
    per = neurons // layers
    out = [LoihiLayer("input", "input", per)]
    for li in range(layers):
        if connectivity == "random":
            width = per // fan_in
            idx = rng.integers(0, width, size=(per, fan_in), dtype=np.int32)
            idx += (np.arange(fan_in, dtype=np.int32) * width)[None, :]
        else:  # local: distinct offsets in a window of 4 * fan_in around the neuron's own position
            window = 4 * fan_in
            base = np.arange(fan_in, dtype=np.int32) * 4
            idx = base[None, :] + rng.integers(0, 4, size=(per, fan_in), dtype=np.int32)
            idx += (np.arange(per, dtype=np.int32) - window // 2)[:, None]
            idx %= per
            idx.sort(axis=1)
        mag = rng.integers(1, 128, size=per * fan_in, dtype=np.int16) * 2
        sign = np.where(rng.random(per * fan_in) < 0.5, -1, 1).astype(np.int16)
        w = sp.csr_matrix(((mag * sign).astype(np.int16), idx.reshape(-1), np.arange(0, per * fan_in + 1, fan_in)),
                          shape=(per, per))
        del idx, mag, sign
        out.append(LoihiLayer(f"layer{li}", "dense", per, weight=w, v_th_mant=64 + li % 3, i_decay=1024, v_decay=256))
    return LoihiNetwork(out, t_sample=100, metadata={"synthetic": True})


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0   # Linux: KiB


def run_once(args) -> dict:
    from snncc.targets.loihi.mapping.partition import map_network

    t0 = time.perf_counter()
    net = synthetic_network(args.neurons, args.fan_in, args.layers, args.connectivity, args.seed)
    t_build = time.perf_counter() - t0
    rss_built = peak_rss_mb()
    synapses = int(sum(lay.weight.nnz for lay in net.layers[1:]))
    t0, c0 = time.perf_counter(), time.process_time()
    cmap = map_network(net)
    t_map, c_map = time.perf_counter() - t0, time.process_time() - c0
    rss = peak_rss_mb()
    return {
        "synthetic": True,
        "connectivity": args.connectivity,
        "neurons": int(sum(lay.n for lay in net.layers[1:])),
        "input_width": net.layers[0].n,
        "synapses": synapses,
        "layers": args.layers,
        "build_seconds": round(t_build, 2),
        "map_seconds": round(t_map, 2),
        "map_cpu_seconds": round(c_map, 2),
        "load_average_1min": round(__import__("os").getloadavg()[0], 2),
        "peak_rss_mb": round(rss, 1),
        "rss_after_build_mb": round(rss_built, 1),
        "peak_rss_bytes_per_synapse": round(rss * 2**20 / synapses, 1),
        "n_cores": cmap.n_cores,
        "n_chips": cmap.n_chips,
        "lower_bound": cmap.lower_bound,
        "lower_bound_method": cmap.lower_bound_method,
        "binding_constraint": cmap.binding_constraint,
        "peak_percent": cmap.peak_percent(),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--neurons", type=int, default=1_000_000)
    ap.add_argument("--fan-in", type=int, default=100)
    ap.add_argument("--layers", type=int, default=10)
    ap.add_argument("--connectivity", choices=("random", "local"), default="random")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--linearity", action="store_true", help="runs at 10/30/100 %% in fresh processes")
    ap.add_argument("--out", help="also write the JSON record here")
    args = ap.parse_args(argv)
    if args.linearity:
        runs = []
        for frac in (0.1, 0.3, 1.0):
            cmd = [sys.executable, __file__, "--neurons", str(int(args.neurons * frac)), "--fan-in", str(args.fan_in),
                   "--layers", str(args.layers), "--connectivity", args.connectivity, "--seed", str(args.seed)]
            runs.append(json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout))
        record = {"runs": runs}
    else:
        record = run_once(args)
    text = json.dumps(record, indent=2)
    print(text)
    if args.out:
        from snncc.atomic import write_text_atomic

        write_text_atomic(args.out, text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
