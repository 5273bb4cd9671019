"""Rockpool's own Xylo Audio 2 flow on a NIR graph, run in XyloSim: the comparison point of
``xylo_side_by_side.py``. Runs in a SEPARATE environment that has rockpool 3.1 (with its nir extra)
and xylosim 0.1.3; snncc never imports Rockpool or samna.

As the NIR paper's notebook: ``nir.read`` -> ``rockpool.nn.modules.from_nir`` -> every module's dt set
to the graph's dt (from_nir guesses dt per layer from r = tau / dt) -> ``syns61201.mapper`` ->
``channel_quantize`` -> ``XyloSim.from_specification``; one sample at a time from a reset state.

    /work/venvs/rockpool/bin/python bench/studies/xylo_rockpool_flow.py GRAPH.nir --dt 1e-4 --inputs x.npz --out counts.npz

``x.npz`` holds ``x`` (B, T, C) spike counts; ``counts.npz`` gets ``counts`` (B, Nout) and the network spec's
dashes and thresholds. ``rockpool.devices.xylo``'s package import needs samna (not installable):
the package is bound bare and only ``syns61201`` is imported.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
import types

import numpy as np


def _bind_xylo_bare():
    spec = importlib.util.find_spec("rockpool.devices.xylo")
    pkg = types.ModuleType("rockpool.devices.xylo")
    pkg.__path__ = list(spec.submodule_search_locations)
    sys.modules["rockpool.devices.xylo"] = pkg
    import rockpool.devices.xylo.syns61201 as audio2

    return audio2


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("graph")
    ap.add_argument("--dt", type=float, required=True)
    ap.add_argument("--inputs", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    audio2 = _bind_xylo_bare()
    import nir
    from rockpool.nn.modules.torch.nir import from_nir
    from rockpool.transform.quantize_methods import channel_quantize

    module = from_nir(nir.read(args.graph))
    for m in module.modules():
        if hasattr(m, "dt"):
            m.dt = args.dt
    spec = audio2.mapper(module.as_graph(), weight_dtype="float", threshold_dtype="float", dash_dtype="float")
    spec = channel_quantize(**spec)
    sim = audio2.XyloSim.from_specification(**spec, dt=args.dt)
    x = np.load(args.inputs, allow_pickle=False)["x"]
    counts = []
    t0 = time.perf_counter()
    for sample in x:
        sim.reset_state()
        out, _, _ = sim(sample.astype(int))
        counts.append(np.asarray(out).sum(axis=0))
    seconds = time.perf_counter() - t0
    np.savez(args.out, counts=np.asarray(counts, np.int64), dash_mem=np.asarray(spec["dash_mem"]),
             dash_syn=np.asarray(spec["dash_syn"]), dash_mem_out=np.asarray(spec["dash_mem_out"]),
             dash_syn_out=np.asarray(spec["dash_syn_out"]), threshold=np.asarray(spec["threshold"]),
             threshold_out=np.asarray(spec["threshold_out"]), seconds=np.asarray(seconds))


if __name__ == "__main__":
    main()
