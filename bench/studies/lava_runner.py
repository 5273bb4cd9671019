"""Run snncc Loihi bundles with lava-dl netx 0.6 in Lava's Loihi 1 fixed-point CPU simulation.

Runs inside the Python 3.10 virtualenv that ``bench/studies/lava_netx_agreement.py`` builds (lava-dl 0.6.0,
lava-nc 0.10.0); it never imports snncc, and snncc never imports it. Called as

    python bench/studies/lava_runner.py JOBS.json

where JOBS.json is a list of ``{"bundle": PATH, "input": X.npy, "output": OUT.npz}``. X is
(B, T, axons) 0/1: every input axon of the bundle's layer 0, always-on bias axons included (the
caller holds them at 1, as a Lava driver of such a bundle must). Per job and per sample b the
runner builds ``lava.lib.dl.netx.hdf5.Network(net_config=bundle)`` afresh (every sample starts
from zero state), connects a ``lava.proc.io.source.RingBuffer`` holding x[b] to the network's
input port and a ``lava.proc.io.sink.RingBuffer`` to every layer block's output, probes each
layer's neuron ``u`` and ``v`` with ``lava.proc.monitor.Monitor``, runs T steps with
``Loihi1SimCfg(select_tag="fixed_pt")`` and writes OUT.npz:

    layer{k}_spikes, layer{k}_current, layer{k}_voltage   (B, T, n)  k = the netx block index + 1
    (netx builds one block per HDF5 dense layer, so k is the bundle's /layer/k)

Lava time step s (1-based) is stored at index s - 1: the source sends x[b, s - 1] at step s, and
a Dense synapse delivers at step s + 1 what it received at step s, so index t here is the same
step t as in snncc's emulator (whose edges deliver one step after the spike). A job that netx
cannot load or Lava cannot run writes ``error`` (one line) and ``stage`` ("load" or "run")
instead. The exit status is 0 when every job wrote its file.
"""

from __future__ import annotations

import json
import sys
import traceback
import warnings

import numpy as np


def _one_line(ex: BaseException) -> str:
    text = f"{type(ex).__name__}: {ex}".strip().splitlines()
    return text[0] if text else type(ex).__name__


def run_sample(bundle: str, x: np.ndarray) -> dict[str, np.ndarray]:
    """One sample (T, axons) through netx + Lava fixed_pt; per layer k: spikes, u, v as (T, n)."""
    from lava.lib.dl import netx
    from lava.magma.core.run_conditions import RunSteps
    from lava.magma.core.run_configs import Loihi1SimCfg
    from lava.proc.io.sink import RingBuffer as Sink
    from lava.proc.io.source import RingBuffer as Source
    from lava.proc.monitor.process import Monitor

    steps = x.shape[0]
    net = netx.hdf5.Network(net_config=bundle)
    source = Source(data=np.ascontiguousarray(x.T.astype(np.int32)))   # (axons, T): time last
    source.s_out.connect(net.inp)
    sinks, monitors = [], []
    for block in net.layers:
        n = int(np.prod(block.out.shape))
        sink = Sink(shape=block.out.shape, buffer=steps)
        block.out.connect(sink.a_in)
        sinks.append(sink)
        mon_u, mon_v = Monitor(), Monitor()
        mon_u.probe(target=block.neuron.u, num_steps=steps)
        mon_v.probe(target=block.neuron.v, num_steps=steps)
        monitors.append((mon_u, mon_v, n))
    try:
        net.run(condition=RunSteps(num_steps=steps), run_cfg=Loihi1SimCfg(select_tag="fixed_pt"))
        out = {}
        for k, (sink, (mon_u, mon_v, n)) in enumerate(zip(sinks, monitors), start=1):
            out[f"layer{k}_spikes"] = np.asarray(sink.data.get()).reshape(n, steps).T.astype(np.uint8)
            for name, mon, var in (("current", mon_u, "u"), ("voltage", mon_v, "v")):
                data = mon.get_data()
                (proc_data,) = data.values()
                out[f"layer{k}_{name}"] = np.asarray(proc_data[var]).reshape(steps, n).astype(np.int64)
        return out
    finally:
        net.stop()


def load_only(bundle: str) -> None:
    """Build the netx network without running it (to tell a load failure from a run failure)."""
    from lava.lib.dl import netx

    netx.hdf5.Network(net_config=bundle)


def run_job(job: dict) -> None:
    x = np.load(job["input"], allow_pickle=False)
    result: dict[str, np.ndarray] = {}
    stage = "load"
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            load_only(job["bundle"])
        result["load_warnings"] = np.array(json.dumps(sorted({str(w.message) for w in caught})))
        stage = "run"
        parts = [run_sample(job["bundle"], x[b]) for b in range(x.shape[0])]
        for key in parts[0]:
            result[key] = np.stack([p[key] for p in parts])
    except Exception as ex:   # a bundle netx cannot load or Lava cannot run: recorded, not fatal
        result = {"error": np.array(_one_line(ex)), "stage": np.array(stage),
                  "traceback": np.array(traceback.format_exc()[-4000:])}
    np.savez(job["output"], **result)


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: lava_runner.py JOBS.json", file=sys.stderr)
        return 2
    with open(argv[0]) as f:
        jobs = json.load(f)
    for job in jobs:
        run_job(job)
        print(f"done {job['bundle']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
