"""ESTIMATE of energy and delay per sample for a paper-sized RSNN (48 -> 450 recurrent -> 28).

SYNTHETIC: random even 8-bit weights (seeded) and random sparse input spikes (rate 0.05 per
channel and step, 270 steps = the paper's tSample), not the trained model and not Braille data.
The threshold (vThMant 400) is chosen so the hidden layer fires at a few percent, as a trained
network does. The paper's own figures (measured on Loihi, 8 cores) are printed beside it.

    python bench/speed/bench_energy.py [--samples 32] [--bundle out.h5] [--json]
    (equivalently: write the bundle, then `snncc report out.h5 --energy --samples 32`)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np


def paper_sized_rsnn(seed: int = 0, vth: int = 400):
    from snncc.targets.loihi.network import LoihiLayer, LoihiNetwork

    rng = np.random.default_rng(seed)

    def w(shape, scale):
        x = (np.round(rng.normal(0.0, scale, size=shape) / 2) * 2).clip(-256, 254).astype(np.int64)
        x[x == 0] = 2
        return x

    common = dict(v_th_mant=vth, i_decay=2315, v_decay=327, ref_delay=1)   # th1: iDecay 2315, vDecay 327
    return LoihiNetwork([
        LoihiLayer("input", "input", 48),
        LoihiLayer("hidden", "dense_rec", 450, weight=w((450, 48), 40.0), weight_rec=w((450, 450), 10.0), **common),
        LoihiLayer("output", "dense", 28, weight=w((28, 450), 20.0), **common),
    ], t_sample=270, metadata={"synthetic": "random weights, paper-sized RSNN"})


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=32)
    ap.add_argument("--rate", type=float, default=0.05)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--bundle", help="also keep the bundle here")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    import snncc.api
    from snncc.errors import SnnccError

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(args.bundle) if args.bundle else Path(tmp) / "rsnn_random.h5"
        from snncc.targets.loihi.bundle.write import write_bundle

        write_bundle(paper_sized_rsnn(args.seed), path)
        try:
            record = snncc.api.report(path, energy=True, samples=args.samples, rate=args.rate, seed=args.seed)
        except SnnccError as err:
            print(f"snncc: error: {err.line()}", file=sys.stderr)
            return 2
        if args.json:
            import json

            from snncc.records import to_jsonable

            print(json.dumps(to_jsonable(record.as_dict()), indent=2, sort_keys=False))
        else:
            from rich.console import Console

            record.render_text(Console(highlight=False))
        return 0


if __name__ == "__main__":
    sys.exit(main())
