"""Relayed bundles: a layer whose fan-in exceeds a core's input axons runs behind the relay layer
the mapper plans (``fanin.py``), and the bundle holds that relayed network.

The relayed network is what the chip and the emulator run. Each relay that cannot take its step
out of the projection's synaptic delay makes every later layer fire one step later; ``RelayPlan``
records, for each layer of the network before relays, its index in the relayed network and that
shift, so results of the relayed run can be read in the original layer order and time
(``unrelay``). tSample and the bundle's output_shift grow by the total shift.

Copy relays are exact (a relay spikes exactly when its source did, one step later); rate relays
are lossy. ``relay_agreement`` measures what the relays change: the relayed run against the same
network without relays (itself checked against the IR), spike for spike per layer and by argmax.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import InternalError
from snncc.targets.loihi.emulation.emulator import EmulationResult, _prediction, emulate
from snncc.targets.loihi.mapping.fanin import row_fan_in
from snncc.targets.loihi.network import LoihiNetwork
from snncc.targets.loihi.mapping.resources import LOIHI1, ChipSpec


@dataclass
class RelayPlan:
    records: list[dict]              # one per relayed layer (fanin.relay_layer's record)
    index: list[int]                 # original layer i -> its index in the relayed network
    shift: list[int]                 # original layer i -> steps its spikes appear later when relayed
    core_map: dict[str, Any] = field(default_factory=dict)

    @property
    def total_shift(self) -> int:
        return int(self.shift[-1]) if self.shift else 0

    @property
    def exact(self) -> bool:
        """Every source of every relayed layer goes through a copy relay."""
        return all(r["through_rate_relays"] == 0 for r in self.records)

    def notes(self) -> list[str]:
        out = []
        for r in self.records:
            out.append(f"layer '{r['layer']}': fan-in {r['fan_in']:,} > {LOIHI1.input_axons_per_core:,} axons a core; "
                       f"relay layer '{r['relay_layer']}' ({r['relay_neurons']:,} neurons): {r['copied_exactly']:,} "
                       f"sources copied exactly, {r['through_rate_relays']:,} through rate relays; {r['accuracy']}; "
                       f"timing {r['timing']}")
        if self.total_shift:
            out.append(f"relays delay the outputs by {self.total_shift} step(s); tSample and output_shift include them")
        return out


def needs_relays(network: LoihiNetwork, chip: ChipSpec = LOIHI1) -> bool:
    """A layer's neuron listens to more sources than a core has input axons."""
    return any(int(row_fan_in(lay).max(initial=0)) > chip.input_axons_per_core for lay in network.layers[1:])


def relay_network(network: LoihiNetwork, chip: ChipSpec = LOIHI1) -> tuple[LoihiNetwork, RelayPlan | None]:
    """(network that runs, plan): ``network`` itself with its core map when no layer needs relays,
    else the mapper's relayed network with tSample, output_shift, population_shifts and the relay
    records in its metadata, and its core map."""
    from snncc.targets.loihi.mapping.partition import map_network

    core_map = map_network(network, chip)
    if not core_map.transforms:
        network.core_map = core_map.to_dict()
        return network, None
    mapped = core_map.network
    relay_of = {r["layer"] for r in core_map.transforms}
    by_record = {r["layer"]: r for r in core_map.transforms}
    index, shift, j, late = [0], [0], 1, 0
    for lay in network.layers[1:]:
        if lay.name in relay_of:
            j += 1                                   # the relay layer sits just before it
            late += int(by_record[lay.name]["timing_shift_steps"])
        index.append(j)
        shift.append(late)
        j += 1
    if j != len(mapped.layers):
        raise InternalError("relayed network layers do not line up with the plan", field="relays")
    meta = dict(mapped.metadata)
    meta["output_shift"] = int(meta.get("output_shift", 0) or 0) + late
    names = meta.get("layer_names") or [lay.name for lay in network.layers]
    pops = dict(meta.get("population_shifts") or {})
    for i, name in enumerate(names[1:], start=1):
        if late and shift[i]:
            pops[name] = int(pops.get(name, 0)) + shift[i]
    meta["population_shifts"] = pops
    meta["layer_names"] = [lay.name for lay in mapped.layers]      # the relay layers included
    meta["fan_in_relays"] = list(core_map.transforms)
    meta["relayed_layer_index"] = index
    relayed = LoihiNetwork(layers=mapped.layers, t_sample=network.t_sample + late, metadata=meta,
                           core_map=core_map.to_dict())
    return relayed, RelayPlan(records=list(core_map.transforms), index=index, shift=shift,
                              core_map=relayed.core_map)


def unrelay(result: EmulationResult, plan: RelayPlan, steps: int) -> EmulationResult:
    """A relayed run read as the network without relays: layer i's records from the relayed layer
    ``plan.index[i]``, ``plan.shift[i]`` steps earlier, ``steps`` long (record "all" runs; the
    relayed run's input padded by ``plan.total_shift`` blank steps)."""
    last = len(plan.index) - 1
    j, s = plan.index[last], plan.shift[last]
    out = result.spikes[j][:, s:s + steps] if j in result.spikes else result.output_spikes[:, s:s + steps]
    counts = out.sum(axis=1, dtype=np.int64)
    res = EmulationResult(output_spikes=np.ascontiguousarray(out), counts=counts, prediction=_prediction(counts),
                          overflow=dict(result.overflow))
    for i, (j, s) in enumerate(zip(plan.index, plan.shift)):
        if j in result.spikes:
            res.spikes[i] = result.spikes[j][:, s:s + steps]
        if j in result.voltage:
            res.voltage[i] = result.voltage[j][:, s:s + steps]
            res.current[i] = result.current[j][:, s:s + steps]
    return res


def emulate_relayed(relayed: LoihiNetwork, plan: RelayPlan, x: np.ndarray, **kwargs) -> EmulationResult:
    """Run the relayed network on ``x`` (B, T, C) and return it read as the network without relays."""
    steps = x.shape[1]
    xp = np.concatenate([x, np.zeros((x.shape[0], plan.total_shift, x.shape[2]), x.dtype)], axis=1) \
        if plan.total_shift else x
    return unrelay(emulate(relayed, xp, record="all", **kwargs), plan, steps)


def relay_agreement(network: LoihiNetwork, relayed: LoihiNetwork, plan: RelayPlan, x: np.ndarray) -> dict[str, Any]:
    """What the relays change on inputs ``x``: per-layer spike agreement and argmax agreement of the
    relayed run against the same network without relays, and whether every spike is equal."""
    plain = emulate(network, x, record="all")
    via = emulate_relayed(relayed, plan, x)
    per_layer = {network.layers[i].name: float(np.mean(plain.spikes[i] == via.spikes[i]))
                 for i in range(1, len(network.layers))}
    equal = all(np.array_equal(plain.spikes[i], via.spikes[i]) for i in range(1, len(network.layers)))
    return {"inputs": f"{x.shape[0]} x {x.shape[1]} steps", "exact_copies_only": plan.exact,
            "spikes_equal": bool(equal), "spike_agreement": per_layer,
            "prediction_agreement": float(np.mean(plain.prediction == via.prediction)),
            "timing_shift_steps": plan.total_shift}
