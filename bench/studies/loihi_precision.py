"""How much precision does braille_zero_2023 need? The per-neuron starting point's ladder and the graph's sensitivity.

Fine-tuning's goal on braille_zero_2023.nir (12 -> 38 recurrent -> 7, zero reset, dt 1e-4) asks a per-layer
bundle (one weight exponent per projection) to agree with the float graph as well as the ``fine`` rule
(every synapse its own exponent) does untuned. This bench measures, on 1,000 held-out seeded random inputs
(density 0.08, 256 steps, the clear-winner rule; the split of bench/studies/finetune_goals.py), without training:

  ladder       Loihi bundles run by the bit-exact emulator: per-layer as lowered; its weights rounded with error
               feedback at the rule's scales; per-neuron scales with nearest rounding; per-neuron scales with
               error-feedback rounding, with a scale per neuron and with at most 8 per layer (what fine-tuning's
               starting points use, targets/loihi/finetune/rescale.py); fine untuned
  sensitivity  the float graph (no chip) with only some weights rounded at per-neuron 8-bit scales with error
               feedback (input weights, recurrent weights, biases, all), and with Gaussian weight noise of
               0.3 % and 1 % (three seeds)
  settings     the error-feedback rounding's damping and the number of calibration inputs
  replication  what --replicas K buys (targets/loihi/lowering/replicate.py): in float, every weight rounded at
               per-neuron scales with K times the levels for the input weights (relays), the hidden neurons'
               outgoing weights (copies) or both; on the chip, the per-neuron start on the replicated network
  int8         the same question for Xylo's weight format: braille_noDelay_noBias_subtract.nir in float with
               only its weights rounded to 127 / 254 / 1,024 levels of each neuron's largest incoming weight
               (nearest; int8 on Xylo has 127 per sign), nothing else changed

    python bench/studies/loihi_precision.py [--out bench/studies/results/loihi_precision.json]

SYNTHETIC inputs; about 2 minutes of CPU.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from snncc.measure.agreement import argmax_agreement  # noqa: E402
from snncc.finetune.inputs import split_inputs  # noqa: E402
from snncc.finetune.teacher import run_teacher  # noqa: E402
from snncc.frontends import LoadOptions, load_model  # noqa: E402
from snncc.passes.current_bias import BiasTerm, current_biases, restore_biases  # noqa: E402
from snncc.rounding import damped, round_with_feedback  # noqa: E402
from snncc.targets.loihi.finetune import rescale  # noqa: E402
from snncc.targets.loihi.finetune.run import network_counts  # noqa: E402
from snncc.targets.loihi.lowering.lower import lower_model  # noqa: E402
from snncc.targets.loihi.options import LoihiOptions  # noqa: E402

GRAPH = ROOT / "tests" / "data" / "nir" / "braille_zero_2023.nir"
SUBTRACT = ROOT / "tests" / "data" / "nir" / "braille_noDelay_noBias_subtract.nir"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=str(ROOT / "bench" / "studies" / "results" / "loihi_precision.json"))
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    t0, c0 = time.time(), time.process_time()
    graph = load_model(GRAPH, LoadOptions(dt=1e-4))
    split = split_inputs(width=12, steps=256, density=0.08, train=2048, validation=500, held_out=1000, seed=args.seed)
    held = split.x[split.held_out]
    low = lower_model(graph, LoihiOptions(scale="per-layer"), t_sample=256)
    names = tuple(c.lif for c in low.layers)
    teacher = run_teacher(low.trained, held, names, voltage=False).counts

    def chip(network) -> float:
        return argmax_agreement(teacher, network_counts(low, 256, network, held)).share

    def calibration(samples: int):
        x = split.x[split.train[:samples]]
        return x, run_teacher(low.trained, x, names, voltage=False).spikes

    x512, s512 = calibration(512)

    def start(per_neuron: bool, grouped: bool = True, cal=None):
        """rescale.rescaled on the per-layer network (``grouped``: at most 8 scales per layer, as fine-tuning)."""
        saved = rescale.scale_groups
        if not grouped:
            rescale.scale_groups = lambda top, _groups: np.asarray(top, np.float64)
        try:
            return rescale.rescaled(low, low.network, *(cal or (x512, s512)), per_neuron=per_neuron)
        finally:
            rescale.scale_groups = saved

    def nearest_per_neuron():
        saved = rescale.round_with_feedback
        rescale.round_with_feedback = lambda h, c, step, lo, hi: np.clip(np.round(c / step), lo, hi)
        try:
            return start(True, grouped=False)
        finally:
            rescale.round_with_feedback = saved

    fine = lower_model(graph, LoihiOptions(scale="fine"), t_sample=256)
    ladder = {
        "per-layer as lowered": chip(low.network),
        "error-feedback rounding at the rule's scales": chip(start(False)),
        "per-neuron scales, nearest rounding": chip(nearest_per_neuron()),
        "per-neuron scales, error-feedback rounding": chip(start(True, grouped=False)),
        "per-neuron scales (at most 8 per layer), error-feedback rounding": chip(start(True)),
        "fine, untuned": chip(fine.network),
    }
    for k, v in ladder.items():
        print(f"  {k}: {v:.3f}", flush=True)

    float_h: dict[int, np.ndarray] = {}

    def layer_h(k: int) -> np.ndarray:
        """Layer k's damped second moments (teacher spikes on the calibration inputs, the float decays), once."""
        if k not in float_h:
            op = low.order.node(low.layers[k].lif)
            a, b = (float(np.ravel(d)[0]) for d in op.decays(low.order.dt))
            float_h[k] = damped(rescale.kernel_moments(low, k, x512, s512, a, b), rescale.DAMPING)
        return float_h[k]

    def set_rows(g, c, m, n_in: int, n_terms: int) -> None:
        """Layer ``c``'s float rows ``m`` (``rescale.float_rows``' column order) written back into ``g``."""
        g.node(c.ff).weight = m[:, :n_in]
        terms = current_biases(g, c.lif)
        if terms:
            restore_biases(g, c.lif, [BiasTerm(t.start, m[:, n_in + j], t.origins) for j, t in enumerate(terms)])
        if c.rec:
            g.node(c.rec).weight = m[:, n_in + n_terms:]

    def float_variant(parts=(), noise=None, seed=0) -> float:
        g = low.trained.copy()
        rng = np.random.default_rng(seed)
        for k, c in enumerate(low.layers):
            w, n_in, n_terms = rescale.float_rows(low, k)
            if noise is not None:
                q = w * (1.0 + noise * rng.standard_normal(w.shape))
                chosen = np.ones(w.shape[1], bool)
            else:
                s = 254.0 / np.max(np.abs(w), axis=1)
                q = 2.0 * round_with_feedback(layer_h(k), w * s[:, None], 2.0, -128, 127) / s[:, None]
                chosen = np.zeros(w.shape[1], bool)
                chosen[:n_in] = "input" in parts
                chosen[n_in:n_in + n_terms] = "biases" in parts
                chosen[n_in + n_terms:] = "recurrent" in parts
            set_rows(g, c, np.where(chosen[None, :], q, w), n_in, n_terms)
        return argmax_agreement(teacher, run_teacher(g, held, names, voltage=False).counts).share

    sensitivity = {f"float, {' + '.join(p)} rounded (per-neuron 8-bit, error feedback)": float_variant(p)
                   for p in (("input",), ("recurrent",), ("biases",), ("input", "recurrent", "biases"))}
    for noise in (0.003, 0.01):
        sensitivity[f"float, {100 * noise:g} % weight noise (3 seeds)"] = [float_variant(noise=noise, seed=s)
                                                                          for s in range(3)]
    for k, v in sensitivity.items():
        print(f"  {k}: {v}", flush=True)

    settings = {}
    for damping in (0.01, 0.1, 0.3):
        saved = rescale.DAMPING
        rescale.DAMPING = damping
        try:
            settings[f"damping {damping:g}"] = chip(start(True))
        finally:
            rescale.DAMPING = saved
    for samples in (256, 2048):
        settings[f"{samples} calibration inputs"] = chip(start(True, cal=calibration(samples)))
    for k, v in settings.items():
        print(f"  {k}: {v:.3f}", flush=True)

    def float_levels(inputs: int, copies: int) -> float:
        """The float graph with every weight rounded (error feedback) at per-neuron scales that ``inputs`` /
        ``copies`` times more levels allow for the input / the hidden neurons' outgoing weights (bias columns
        keep 8 bits): what --replicas lets a chip hold, before any chip arithmetic."""
        g = low.trained.copy()
        for k, c in enumerate(low.layers):
            w, n_in, n_terms = rescale.float_rows(low, k)
            k_in = inputs if k == 0 else copies
            parts = [np.abs(w[:, :n_in]).max(axis=1) / k_in, np.abs(w[:, n_in:n_in + n_terms]).max(axis=1, initial=0)]
            if w.shape[1] > n_in + n_terms:
                parts.append(np.abs(w[:, n_in + n_terms:]).max(axis=1) / copies)
            s = 254.0 / np.maximum.reduce(parts)
            h = layer_h(k)
            top = np.full(w.shape[1], 127.0 * copies)
            top[:n_in], top[n_in:n_in + n_terms] = 127.0 * k_in, 127.0
            set_rows(g, c, 2.0 * round_with_feedback(h, w * s[:, None], 2.0, -top, top) / s[:, None], n_in, n_terms)
        return argmax_agreement(teacher, run_teacher(g, held, names, voltage=False).counts).share

    def replicated_start(copies: int) -> float:
        """The chip: --replicas ``copies``, per-layer, fine-tuning's per-neuron start (no training)."""
        rl = lower_model(graph, LoihiOptions(scale="per-layer", replicas=copies), t_sample=256)
        rn = tuple(c.lif for c in rl.layers)
        net = rescale.rescaled(rl, rl.network, x512, run_teacher(rl.trained, x512, rn, voltage=False).spikes)
        return argmax_agreement(teacher, network_counts(rl, 256, net, held)).share

    replication = {}
    for k in (2, 4, 8):
        replication[f"float, {k}x levels: input relays and hidden copies"] = float_levels(k, k)
        replication[f"float, {k}x levels: input relays only"] = float_levels(k, 1)
        replication[f"float, {k}x levels: hidden copies only"] = float_levels(1, k)
    for k in (1, 2, 4, 8):
        replication[f"chip, --replicas {k}, per-neuron start (untrained)"] = replicated_start(k)
    for k, v in replication.items():
        print(f"  {k}: {v:.3f}", flush=True)

    sub = load_model(SUBTRACT, LoadOptions(dt=1e-4, reset="subtract"))
    pops = tuple(name for name, op in sub.items() if type(op).__name__ == "LIF")
    sub_teacher = run_teacher(sub, held, pops, voltage=False).counts

    def levels_of(levels: int) -> float:
        g = sub.copy()
        for lif in pops:
            denses = [p for p in g.predecessors(lif) if type(g.node(p)).__name__ == "Dense"]
            top = np.max(np.stack([np.abs(g.node(p).weight).max(axis=1) for p in denses]), axis=0)
            scale = levels / np.where(top > 0, top, 1.0)
            for p in denses:
                g.node(p).weight = np.round(g.node(p).weight * scale[:, None]) / scale[:, None]
        return argmax_agreement(sub_teacher, run_teacher(g, held, pops, voltage=False).counts).share

    int8 = {f"{SUBTRACT.name}, float, weights at {n} levels per neuron": levels_of(n) for n in (127, 254, 1024)}
    for k, v in int8.items():
        print(f"  {k}: {v:.3f}", flush=True)

    out = {"machine": {"platform": platform.platform(), "python": platform.python_version()},
           "graph": GRAPH.name,
           "inputs": "SYNTHETIC: 1,000 held-out seeded random spike trains, density 0.08, 256 steps",
           "ladder": ladder, "sensitivity": sensitivity, "settings": settings, "replication": replication,
           "int8": int8,
           "cpu_s": time.process_time() - c0, "wall_s": time.time() - t0}
    Path(args.out).write_text(json.dumps(out, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
