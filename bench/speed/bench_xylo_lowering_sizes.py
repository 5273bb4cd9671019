"""The Xylo lowering's CPU time per synapse across network sizes the chip holds, in one run.

Seeded chains 12 -> N (recurrent) -> 7, the shape of the Braille RSNN (alpha 0.75, beta 0.85; SYNTHETIC weights
scaled so the hidden population fires a few percent of its steps), lowered for Xylo Audio 2 with the default
calibration (256 seeded samples of 256 steps):

* ``auto`` (the default rule: every candidate measured, the best kept) on dense chains, N from 8 to 48: the
  identified and relayed rules fit every neuron on all of its population's channels, so a hidden neuron reaches
  the whole population (and its relays): Audio 2's fan-out of 64 bounds N there;
* ``direct`` on sparse chains, N from 64 to 992 (each hidden neuron 16 recurrent targets): the rule the chip
  holds at those sizes.

Per network: the lowering's CPU seconds (this process, ``time.process_time``, its thread pools on one thread as
the lowering runs them), the synapses of its spec.npz (non-zero weights of the three matrices), and CPU
microseconds per synapse; per family the largest over the smallest of those. ``numba``'s kernels are compiled (or
loaded) before timing.

    python bench/speed/bench_xylo_lowering_sizes.py               # -> bench/speed/results/xylo_lowering_sizes.json
    python bench/speed/bench_xylo_lowering_sizes.py --quick       # fewer sizes, 64 calibration samples
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from snncc.ir import LIF, Dense, Graph, Input, Output, Readout, validate  # noqa: E402
from snncc.targets.xylo.lowering.lower import lower  # noqa: E402
from snncc.targets.xylo.options import XyloOptions  # noqa: E402

AUTO_SIZES = (8, 16, 24, 32, 48)
DIRECT_SIZES = (64, 128, 256, 512, 992)
RECURRENT_TARGETS = 16


def chain(n: int, seed: int, targets: int | None = None, dt: float = 1e-4) -> Graph:
    """12 -> n -> 7 with Euler decays 0.75 / 0.85 (the output 0.45 / 0.7); ``targets``: recurrent targets per
    hidden neuron (None: dense)."""
    rng = np.random.default_rng(seed)
    w_rec = rng.normal(0, 0.5 / np.sqrt(n), (n, n))
    if targets is not None:
        mask = np.zeros((n, n), bool)
        for j in range(n):
            mask[rng.choice(n, min(targets, n), replace=False), j] = True
        w_rec = np.where(mask, rng.normal(0, 0.5 / np.sqrt(targets), (n, n)), 0.0)
    g = Graph(dt, name=f"chain{n}")
    g.add("input", Input(12))
    g.add("w_in", Dense(rng.normal(0.3, 0.6, (n, 12))))
    g.add("hidden", LIF(n, dt / 0.25, dt / 0.15, 1.0, reset="subtract", discretisation="euler"))
    g.add("w_rec", Dense(w_rec))
    g.add("w_out", Dense(rng.normal(0.2, 2.0 / np.sqrt(n), (7, n))))
    g.add("out", LIF(7, dt / 0.55, dt / 0.3, 1.0, reset="subtract", discretisation="euler"))
    g.add("readout", Readout(7))
    g.add("output", Output(7))
    g.connect("input", "w_in")
    g.connect("w_in", "hidden")
    g.connect("hidden", "w_rec", delay=1)
    g.connect("w_rec", "hidden")
    g.connect("hidden", "w_out")
    g.connect("w_out", "out")
    g.connect("out", "readout")
    g.connect("readout", "output")
    return validate(g)


def one(n: int, rule: str, targets: int | None, samples: int | None) -> dict:
    graph = chain(n, seed=n, targets=targets)
    t0 = time.process_time()
    low = lower(graph, XyloOptions(rule=rule, calibration_samples=samples))
    cpu = time.process_time() - t0
    spec = low.xylo_spec
    synapses = int(sum(np.count_nonzero(w) for w in (spec.weights_in, spec.weights_rec, spec.weights_out)))
    row = {"hidden_in_model": n, "hidden_on_chip": spec.n_hidden, "rule_chosen": low.rule, "synapses": synapses,
           "cpu_s": cpu, "cpu_us_per_synapse": 1e6 * cpu / synapses}
    print(f"{rule:6s} N {n:4d} -> {spec.n_hidden:4d} hidden, {synapses:7,d} synapses, {cpu:6.2f} s CPU, "
          f"{row['cpu_us_per_synapse']:7.1f} us/synapse  [{low.rule}]", flush=True)
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="three sizes per family, 64 calibration samples")
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "speed" / "results" / "xylo_lowering_sizes.json")
    args = ap.parse_args(argv)
    samples = 64 if args.quick else None
    auto, direct = (AUTO_SIZES[::2], DIRECT_SIZES[::2]) if args.quick else (AUTO_SIZES, DIRECT_SIZES)
    lower(chain(8, 0), XyloOptions(rule="relayed", calibration_samples=4, time_steps=16))   # kernels compiled first
    families = {"auto (dense chains)": [one(n, "auto", None, samples) for n in auto],
                f"direct (sparse chains, {RECURRENT_TARGETS} recurrent targets)":
                    [one(n, "direct", RECURRENT_TARGETS, samples) for n in direct]}
    spread = {name: max(r["cpu_us_per_synapse"] for r in rows) / min(r["cpu_us_per_synapse"] for r in rows)
              for name, rows in families.items()}
    for name, value in spread.items():
        print(f"{name}: CPU per synapse, largest over smallest: {value:.2f}x")
    result = {"what": "Xylo lowering: CPU seconds per synapse of the written spec across sizes (Xylo Audio 2)",
              "calibration_samples": samples or "default (256)", "families": families,
              "largest_over_smallest_per_synapse": spread,
              "machine": {"cores": os.cpu_count(), "platform": platform.platform(), "load": os.getloadavg()}}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
