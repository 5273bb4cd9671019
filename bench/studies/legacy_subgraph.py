"""Why the NIR paper's 2023 Braille sub-graph (tests/data/nir/braille_subgraph_2023.nir) is refused.

The file was written by hand from the trained snnTorch RSynaptic network (NIR repository, paper/03_rnn/
2310_model_rework.ipynb at commit a440c28) as

    tau_syn = 1 / (1 - beta),  tau_mem = 1 / (1 - alpha),  r = 1,  w_in = 1 (not stored: NIR 0.2's
    writer dropped w_in),  no dt

while snnTorch's alpha is the SYNAPTIC decay and beta the MEMBRANE decay (alpha_r 0.55, beta_r 0.9,
alpha_out 0.5, beta_out 0.55 in parameters_ref_20231011.json). The same trained weights, exported
correctly, are braille_zero_2023.nir (dt = 1e-4, r = tau_mem/dt, w_in = tau_syn/dt). This script reads
the file four ways, bypassing snncc's refusal, and prints each reading's float spike rates and its
agreement with braille_zero_2023.nir at dt = 1e-4:

    literal, dt 1e-4    what `snncc compile ... --dt 1e-4` read before the refusal
    literal, dt 1       the time constants taken in steps (the dt the file implies)
    gains, dt 1         plus snnTorch's unit gains (w_in = tau_syn, r = tau_mem, in steps)
    gains + swap, dt 1  plus tau_syn and tau_mem exchanged: the trained network

Inputs: seeded random spike trains (density 0.08) and SYNTHETIC Braille letters (snncc's generator,
the NIR paper's 7 letters Space A E I O U Y, threshold 1, 5 ms bins, ON | OFF per taxel = 12
channels, 256 steps), both SYNTHETIC.

    python bench/studies/legacy_subgraph.py [--samples 40] [--json]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "nir"
LETTERS = ("Space", "A", "E", "I", "O", "U", "Y")


def reading(swap: bool, gains: bool, dt: float):
    """The sub-graph file as an IR graph: NIR 0.2's w_in = 1 (or the restored gains), taus as stored or swapped."""
    import h5py
    import nir
    from nir.serialization import hdf2dict

    from snncc.frontends.nir import graph_from_nir
    from snncc.frontends.nir_legacy import normalise

    with h5py.File(DATA / "braille_subgraph_2023.nir", "r") as f:
        raw = hdf2dict(f["node"])
    normalise(raw, "", [], "braille_subgraph_2023.nir")
    raw["type_check"] = False
    for lif in (raw["nodes"]["hidden"]["nodes"]["lif"], raw["nodes"]["lif2"]):
        if swap:
            lif["tau_syn"], lif["tau_mem"] = lif["tau_mem"].copy(), lif["tau_syn"].copy()
        lif["w_in"] = lif["tau_syn"].copy() if gains else np.ones_like(lif["tau_syn"])
        if gains:
            lif["r"] = lif["tau_mem"].copy()
    return graph_from_nir(nir.dict2NIRNode(raw), dt=dt, source="braille_subgraph_2023.nir")


def task_like(samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(N, 256, 12) SYNTHETIC Braille letters of the NIR paper's subset, ON | OFF events per taxel, and
    their labels as the graphs' output index (Space 0, A 1, E 2, I 3, O 4, U 5, Y 6)."""
    from snncc import api
    from snncc.data.letters import CLASSES

    with tempfile.TemporaryDirectory() as tmp:
        api.data_synth(out=Path(tmp) / "b", repetitions=max(1, -(-samples // len(LETTERS))), thresholds="1")
        api.data_encode(Path(tmp) / "b", out=Path(tmp) / "ev.npz", threshold=1, bin_ms=5)
        with np.load(Path(tmp) / "ev.npz", allow_pickle=False) as d:
            x, labels = d["inputs"], d["labels"]
    wanted = [CLASSES.index(c) for c in LETTERS]
    keep = np.isin(labels, wanted)
    x, y = x[keep][:samples, :256], labels[keep][:samples]
    return (x[..., 0::2] | x[..., 1::2]).astype(np.uint8), np.array([wanted.index(v) for v in y])


def measure(samples: int) -> dict:
    from snncc.frontends import LoadOptions, load_model
    from snncc.ir.simulate import simulate

    rng = np.random.default_rng(0)
    letters, labels = task_like(samples)
    inputs = {"random spike trains, density 0.08": (rng.random((samples, 256, 12)) < 0.08).astype(np.uint8),
              "SYNTHETIC Braille letters": letters}
    trained = load_model(DATA / "braille_zero_2023.nir", LoadOptions(dt=1e-4))
    readings = {"literal, dt 1e-4": (False, False, 1e-4), "literal, dt 1": (False, False, 1.0),
                "gains, dt 1": (False, True, 1.0), "gains + swap, dt 1": (True, True, 1.0)}
    out: dict = {"inputs": {k: list(v.shape) for k, v in inputs.items()}, "results": []}
    for label, x in inputs.items():
        ref = simulate(trained, x, record="spikes")
        row = {"inputs": label, "braille_zero_2023 rates": {k: float(v.mean()) for k, v in ref.spikes.items()}}
        if x is letters:   # how the trained network does on the synthetic letters (not the paper's recordings)
            row["braille_zero_2023 accuracy on the SYNTHETIC letters"] = float((np.asarray(ref.prediction) == labels).mean())
        for name, (swap, gains, dt) in readings.items():
            g = reading(swap, gains, dt)
            res = simulate(g, x, record="spikes")
            hidden, output = res.spikes["hidden.lif"], res.spikes["lif2"]
            row[name] = {
                "hidden rate": float(hidden.mean()), "output rate": float(output.mean()),
                "argmax agreement with braille_zero_2023": float(np.mean(np.asarray(res.prediction)
                                                                         == np.asarray(ref.prediction))),
                "spike entries equal (hidden, output)": [float(np.mean(np.asarray(hidden)
                                                                       == np.asarray(ref.spikes["lif1.lif"]))),
                                                          float(np.mean(np.asarray(output)
                                                                        == np.asarray(ref.spikes["lif2"])))]}
        out["results"].append(row)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=40)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    res = measure(args.samples)
    if args.json:
        print(json.dumps(res, indent=2))
        return
    for row in res["results"]:
        ref = row["braille_zero_2023 rates"]
        acc = row.get("braille_zero_2023 accuracy on the SYNTHETIC letters")
        print(f"{row['inputs']} (SYNTHETIC): braille_zero_2023 rates hidden {ref['lif1.lif']:.4f}, output {ref['lif2']:.4f}"
              + (f", accuracy {acc:.3f}" if acc is not None else ""))
        for name, r in row.items():
            if isinstance(r, dict) and "hidden rate" in r:
                print(f"  {name:20s} hidden {r['hidden rate']:.4f}  output {r['output rate']:.4f}  argmax agreement "
                      f"{r['argmax agreement with braille_zero_2023']:.3f}  spikes equal "
                      f"{r['spike entries equal (hidden, output)'][0]:.4f} / {r['spike entries equal (hidden, output)'][1]:.4f}")


if __name__ == "__main__":
    main()
