"""``profile`` of a Loihi bundle (``snncc compare``): cores against the chip, real time and energy ESTIMATE, NeuroBench.

resources   cores used against one Loihi 1 chip's 128 (and the chips the map needs), neurons and synapses as
            mapped
real time   the ESTIMATE of ``estimate/energy.py`` (Davies et al. 2018 Table 2 per-operation costs): the
            sample's delay against its duration (steps x dt), at the event rates of the inputs given
energy      the same ESTIMATE's dynamic energy per sample, with its source
NeuroBench  from the bundle's own emulation (every layer recorded): synapses as stored (mantissas: a weight
            rounded to 0 is zero; the model's units only, always-on bias sources left out, as NeuroBench
            leaves biases out), activations of every layer; footprint = synaptic memory as mapped (the core
            map's synapse bits) plus each compartment's two 24-bit state registers (u, v)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

from snncc.targets.kit import SnnccError

COST_SOURCE = "Davies et al. 2018, IEEE Micro 38(1), Table 2: pre-silicon per-operation costs, dynamic energy only"
CORES_PER_CHIP = 128
STATE_BYTES_PER_NEURON = 6          # u and v, 24 bits each


def _projections(network: Any) -> list[Any]:
    from snncc.targets.kit.neurobench import Projection

    out = []
    for i, layer in enumerate(network.layers[1:], start=1):
        prev = network.layers[i - 1]
        if layer.weight is not None:
            out.append(Projection(f"L{i - 1}", f"L{i}", np.asarray(layer.weight)[:layer.model_n, :prev.model_n]))
        if layer.weight_rec is not None:
            out.append(Projection(f"L{i}", f"L{i}", np.asarray(layer.weight_rec)[:layer.model_n, :layer.model_n], 1))
    return out


def profile_bundle(graph: Any, source: Path, inputs: np.ndarray,
                   progress: Callable[[int], None] | None = None) -> Any:
    """The ``Profile`` of the bundle at ``source`` on ``inputs`` (B, T, C) in the graph's input layout."""
    from snncc.targets.kit.neurobench import Tally, from_tally
    from snncc.targets.kit.profile import EnergyEstimate, Profile, RealTime, Resource
    from snncc.targets.loihi.bundle.read import read_bundle
    from snncc.targets.loihi.emulation.emulator import emulate
    from snncc.targets.loihi.emulation.fit import fit_to_bundle
    from snncc.targets.loihi.estimate.energy import estimate_energy, merge
    from snncc.targets.loihi.mapping.partition import map_network

    network = read_bundle(Path(source))
    x, fit = fit_to_bundle(np.asarray(inputs), network, str(source))
    try:
        cmap = map_network(network)
    except SnnccError as err:
        raise err.with_file(str(source)) from None
    projections = _projections(network)
    populations = [f"L{i}" for i in range(1, len(network.layers))]
    tally = Tally(projections, populations)
    parts = []
    for start in range(0, x.shape[0], 16):
        part = x[start:start + 16]
        res = emulate(network, part, record="all")
        parts.append(estimate_energy(network, cmap, res.spikes, res.current, res.voltage, input_note="the inputs given"))
        activity = {"L0": part[..., :network.layers[0].model_n]}
        for i in range(1, len(network.layers)):
            spikes = res.spikes.get(i)
            if spikes is not None:
                activity[f"L{i}"] = spikes[..., :network.layers[i].model_n]
        tally.add(activity)
        if progress is not None:
            progress(int(part.shape[0]))
    estimate = merge(parts)
    totals = cmap.totals()
    synapse_bits = int(totals.get("synapse_bits", 0))
    neurons = int(sum(layer.model_n for layer in network.layers[1:]))
    footprint = synapse_bits // 8 + STATE_BYTES_PER_NEURON * neurons
    figures = from_tally(tally, footprint, f"synaptic memory as mapped ({synapse_bits:,} bits) and {neurons} "
                                           f"compartments' u and v (24 bits each)")
    dt = float(graph.dt)
    duration_ms = 1000.0 * dt * float(x.shape[1])
    delay = float(estimate.delay_ms)
    real_time = RealTime(delay <= duration_ms, duration_ms / delay if delay > 0 else float("inf"), None,
                         f"ESTIMATE: {COST_SOURCE}; a sample of {x.shape[1]} steps of dt {dt:g} s lasts "
                         f"{duration_ms:.3g} ms")
    energy = EnergyEstimate(float(estimate.energy_uj["total"]), delay, COST_SOURCE)
    resources = [Resource("cores", int(cmap.n_cores), CORES_PER_CHIP * int(cmap.n_chips)),
                 Resource("chips", int(cmap.n_chips)), Resource("neurons", neurons),
                 Resource("synapses", int(sum(int(np.count_nonzero(p.weight)) for p in projections)))]
    notes = ["energy and delay are ESTIMATES from a pre-silicon cost table, not measurements"]
    if fit:
        notes.append(f"inputs: {fit}")
    return Profile("loihi", resources, figures, real_time, energy, notes)
