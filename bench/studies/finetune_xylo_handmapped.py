"""Fine-tuning through Xylo Audio 2's arithmetic, measured on a PLAIN HAND MAPPING of the subtract-reset
Braille RSNN (not the Xylo target's lowering, which is built elsewhere). Long: not a test.

    python bench/studies/finetune_xylo_handmapped.py --out /tmp/xylo_ft.json

Mapping (IR graph of braille_noDelay_noBias_subtract.nir, dt 1e-4, Euler): the hidden LIF -> Xylo's hidden
neurons, the output LIF -> Xylo's output neurons (every hidden neuron an output-expansion neuron);
decays: the bit shift d whose 1 - 2**-d is nearest to the IR's alpha / beta; Xylo's current is alpha times
the IR's (it decays after adding), so input and recurrent weights are divided by alpha; per layer one
scale (threshold 1 -> ``--threshold`` integer units), int8 weights with one shift per matrix. Xylo delivers
hidden -> output one step later than the IR graph. Inputs: seeded random spikes (density 0.08, 256 steps;
SYNTHETIC), 1,000 held out; agreement = argmax agreement with the float graph, clear winners only.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
GRAPH = Path(__file__).resolve().parents[2] / "tests" / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"


def nearest_dash(decay: np.ndarray) -> np.ndarray:
    d = np.arange(16)
    return np.array([d[np.argmin(np.abs((1 - 2.0 ** -d) - a))] for a in np.ravel(decay)], np.uint8)


def int8(w: np.ndarray, scale: float) -> tuple[np.ndarray, int]:
    shift = max(0, int(np.ceil(np.log2(max(np.abs(w).max() * scale, 1e-9) / 127))))
    return np.clip(np.rint(w * scale / 2 ** shift), -128, 127).astype(np.int8), shift


def hand_mapped(g, threshold: int):
    from snncc.targets.xylo.spec import XyloSpec

    h, o = g.node("lif1.lif"), g.node("lif2")
    a_h, b_h = h.decays(g.dt)
    a_o, b_o = o.decays(g.dt)
    s_h = threshold / float(np.mean(h.threshold))
    s_o = threshold / float(np.mean(o.threshold))
    w_in, sh_in = int8(g.node("fc1").weight.T / np.asarray(a_h)[None, :], s_h)
    w_rec, sh_rec = int8(g.node("lif1.w_rec").weight.T / np.asarray(a_h)[None, :], s_h)
    w_out, sh_out = int8(g.node("fc2").weight.T / np.asarray(a_o)[None, :], s_o)
    n, m = h.n, o.n
    full = lambda v, k: np.broadcast_to(np.asarray(v, np.float64), (k,))
    spec = XyloSpec(weights_in=w_in, weights_rec=w_rec, weights_out=w_out,
                    dash_mem=nearest_dash(full(b_h, n)), dash_syn=nearest_dash(full(a_h, n)),
                    dash_syn_2=nearest_dash(full(a_h, n)), dash_mem_out=nearest_dash(full(b_o, m)),
                    dash_syn_out=nearest_dash(full(a_o, m)), threshold=np.rint(full(h.threshold, n) * s_h).astype(np.int16),
                    threshold_out=np.rint(full(o.threshold, m) * s_o).astype(np.int16), bias=np.zeros(n, np.int16),
                    bias_out=np.zeros(m, np.int16), weight_shift_in=sh_in, weight_shift_rec=sh_rec,
                    weight_shift_out=sh_out, aliases=[[] for _ in range(n)], dt=g.dt)
    return spec


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--threshold", type=int, default=2048)
    ap.add_argument("--train", type=int, default=2048)
    ap.add_argument("--epochs", type=int, default=6)
    ap.add_argument("--lr-weights", type=float, default=0.3)
    ap.add_argument("--lr-thresholds", type=float, default=10.0)
    ap.add_argument("--lr-biases", type=float, default=3.0)
    ap.add_argument("--w-windows", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    import torch

    torch.set_num_threads(1)
    from snncc.finetune.engine import FinetuneConfig
    from snncc.finetune.inputs import split_inputs
    from snncc.finetune.loss import LossWeights
    from snncc.frontends import LoadOptions, load_model
    from snncc.targets.xylo.finetune.tuning import finetune_xylo

    g = load_model(GRAPH, LoadOptions(dt=1e-4, reset="subtract"))
    spec = hand_mapped(g, args.threshold)
    split = split_inputs(width=12, steps=256, density=0.08, train=args.train, validation=500, held_out=1000,
                         seed=args.seed)
    config = FinetuneConfig(epochs=args.epochs, seed=args.seed, loss=LossWeights(windows=args.w_windows),
                            lr={"weights": args.lr_weights, "thresholds": args.lr_thresholds, "decays": 0.0,
                                "biases": args.lr_biases})
    last = [0.0]

    def progress(done, total, phase):
        if time.time() - last[0] > 30 or done == total:
            last[0] = time.time()
            print(f"  {phase} {done}/{total}", flush=True)

    cpu0, wall0 = time.process_time(), time.time()
    out = finetune_xylo(spec, g, split, hidden={"lif1.lif": np.arange(40)}, output="lif2", config=config,
                        progress=progress)
    result = {"mapping": "PLAIN HAND MAPPING (bench/studies/finetune_xylo_handmapped.py), not the Xylo target's lowering",
              "settings": {k: str(v) for k, v in vars(args).items()},
              "dash": {"syn": int(spec.dash_syn[0]), "mem": int(spec.dash_mem[0]), "syn_out": int(spec.dash_syn_out[0]),
                       "mem_out": int(spec.dash_mem_out[0])},
              "record": out.record.as_dict(), "cpu_s": time.process_time() - cpu0, "wall_s": time.time() - wall0}
    args.out.write_text(json.dumps(result, indent=1, default=float))
    print("\n".join(out.record.lines()))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
