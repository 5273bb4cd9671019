"""NIR test graphs for the Loihi scaling goals: an RSNN 48 -> N dense-recurrent -> 28, seeded.

    nir.NIRGraph: Input(48) -> Affine(48 -> N) -> CubaLIF(N) <-> Affine(N -> N) (recurrent)
                  CubaLIF(N) -> Affine(N -> 28) -> CubaLIF(28) -> Output(28)

CubaLIF: tau_syn 5 ms, tau_mem 20 ms, threshold 1, v_leak 0, written the way snnTorch exports a model with
dt = 1 ms (r = tau_mem / dt, w_in = tau_syn / dt), so that at ``--dt 1e-3`` a weight is the current a spike
adds in one step. Weights ~ N(0, 1 / fan-in) (variance), biases N(0, 0.01). The 1-neuron graph is
Input(1) -> Affine(1 -> 1) -> CubaLIF(1) -> Output(1) with the same neuron.

    python bench/speed/loihi_rsnn_graphs.py --hidden 450 900 1800 3600 --out bench/speed/.graphs
    snncc compile bench/speed/.graphs/rsnn_3600.nir --dt 1e-3 --target loihi -o rsnn.net
"""

from __future__ import annotations

import argparse
from pathlib import Path

import nir
import numpy as np

DT = 1e-3
TAU_SYN, TAU_MEM = 5e-3, 20e-3
N_IN, N_OUT = 48, 28


def cuba(n: int) -> nir.CubaLIF:
    return nir.CubaLIF(tau_syn=np.full(n, TAU_SYN), tau_mem=np.full(n, TAU_MEM), r=np.full(n, TAU_MEM / DT),
                       v_leak=np.zeros(n), v_threshold=np.ones(n), w_in=np.full(n, TAU_SYN / DT))


def affine(rng: np.random.Generator, n_out: int, n_in: int) -> nir.Affine:
    return nir.Affine(weight=rng.normal(0.0, np.sqrt(1.0 / n_in), (n_out, n_in)), bias=rng.normal(0.0, 0.1, n_out))


def rsnn(hidden: int, seed: int = 0) -> nir.NIRGraph:
    """48 -> ``hidden`` dense-recurrent -> 28 (module docstring)."""
    rng = np.random.default_rng(seed)
    nodes = {"input": nir.Input(np.array([N_IN])), "fc_in": affine(rng, hidden, N_IN), "lif": cuba(hidden),
             "fc_rec": affine(rng, hidden, hidden), "fc_out": affine(rng, N_OUT, hidden), "lif_out": cuba(N_OUT),
             "output": nir.Output(np.array([N_OUT]))}
    edges = [("input", "fc_in"), ("fc_in", "lif"), ("lif", "fc_rec"), ("fc_rec", "lif"), ("lif", "fc_out"),
             ("fc_out", "lif_out"), ("lif_out", "output")]
    return nir.NIRGraph(nodes=nodes, edges=edges, type_check=False)


def one_neuron(seed: int = 0) -> nir.NIRGraph:
    rng = np.random.default_rng(seed)
    nodes = {"input": nir.Input(np.array([1])), "fc": nir.Affine(weight=np.array([[1.5]]), bias=rng.normal(0, 0.1, 1)),
             "lif": cuba(1), "output": nir.Output(np.array([1]))}
    return nir.NIRGraph(nodes=nodes, edges=[("input", "fc"), ("fc", "lif"), ("lif", "output")], type_check=False)


def write(graph: nir.NIRGraph, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    nir.write(str(path), graph)
    return path


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--hidden", type=int, nargs="+", default=[450, 900, 1800, 3600])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("bench/speed/.graphs"))
    args = ap.parse_args(argv)
    for n in args.hidden:
        print(write(rsnn(n, args.seed), args.out / f"rsnn_{n}.nir"))
    print(write(one_neuron(args.seed), args.out / "one_neuron.nir"))


if __name__ == "__main__":
    main()
