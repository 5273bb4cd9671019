"""ESTIMATE of energy and delay per sample on Loihi 1, from an emulation and a core map.

Counts per sample (from the emulator's spikes, u and v of every layer):

    synaptic ops       each spike x its nonzero synapses (all projections it feeds)
    neuron updates     every compartment every step; active = spiked, or u or v changed
                       (at t = 0: nonzero), inactive otherwise
    spike messages     one per (spike, destination core it has synapses on); a message within
                       a tile costs one in-tile transfer, else |dx| east-west + |dy| north-south
                       tile hops

Geometry assumed (stated in every report): 4 cores per tile, each chip an 8 (east-west) x 4
(north-south) mesh of tiles, cores placed in id order (core k -> tile (k mod 128) // 4, tile t
-> x = t mod 8, y = t // 8), chips side by side east-west; input spikes injected at tile (0, 0)
of chip 0 (the host / embedded-CPU side; their transfer is counted as hops from there).

Costs: Davies et al. 2018 Table 2 (pre-silicon, 0.75 V) from ``ChipSpec.energy``.
    energy/sample = sum of counts x energy per op  (dynamic only: no static or x86 power)
    step time     = max over cores of (synops x 3.5 ns + active x 8.4 + inactive x 5.3 + messages
                    sent x their transfer time) + barrier (113 ns for 1 tile .. 465 ns for 32
                    tiles, linear in the tiles in use; extrapolated linearly beyond 32)
    delay/sample  = sum of the step times of its steps
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import InternalError
from snncc.targets.loihi.mapping.coremap import CoreMap
from snncc.targets.loihi.network import LoihiNetwork

PAPER_RSNN = {
    "source": "paper (measured on Loihi, RSNN th1)",
    "cores": 8,
    "power_mw": 31.0,
    "energy_uj_per_sample": 71.0,
    "delay_ms_per_sample": 2.3,
    "accuracy_loihi_percent": 78.32,
    "accuracy_pytorch_percent": 79.90,
}

GEOMETRY = ("4 cores per tile; each chip an 8 (east-west) x 4 (north-south) tile mesh; cores placed in "
            "id order; chips side by side east-west; input spikes injected at tile (0,0) of chip 0")


@dataclass
class EnergyEstimate:
    label: str
    samples: int
    steps: int
    n_cores: int
    tiles_used: int
    counts: dict[str, float]          # mean per sample
    energy_uj: dict[str, float]       # mean per sample, by component and total
    delay_ms: float                   # mean per sample
    step_ns: dict[str, float]         # mean / max step time, barrier
    power_mw: float                   # dynamic energy / delay
    input_note: str
    assumptions: list[str] = field(default_factory=list)
    paper: dict[str, Any] = field(default_factory=lambda: dict(PAPER_RSNN))

    def to_dict(self) -> dict[str, Any]:
        return {
            "label": self.label, "samples": self.samples, "steps_per_sample": self.steps,
            "n_cores": self.n_cores, "tiles_used": self.tiles_used,
            "counts_per_sample": self.counts, "energy_uj_per_sample": self.energy_uj,
            "delay_ms_per_sample": self.delay_ms, "step_ns": self.step_ns,
            "dynamic_power_mw": self.power_mw, "inputs": self.input_note,
            "assumptions": self.assumptions, "paper_measurement": self.paper,
        }

    def render_text(self, console) -> None:
        from rich.table import Table

        console.print(f"[bold]{self.label}[/bold]")
        console.print(f"inputs: {self.input_note}; {self.samples} sample(s) x {self.steps} steps; "
                      f"{self.n_cores} cores on {self.tiles_used} tile(s)")
        t = Table(title="per sample (mean)")
        t.add_column("count")
        t.add_column("value", justify="right")
        for k, v in self.counts.items():
            t.add_row(k.replace("_", " "), f"{v:,.1f}")
        console.print(t)
        cmp = Table(title="ESTIMATE beside the paper's measurement")
        for col in ("", "snncc ESTIMATE (dynamic, Table 2)", "paper, measured (RSNN th1)"):
            cmp.add_column(col, justify="right")
        cmp.add_row("cores", str(self.n_cores), str(self.paper["cores"]))
        cmp.add_row("energy per sample (uJ)", f"{self.energy_uj['total']:.3g}", f"{self.paper['energy_uj_per_sample']}")
        cmp.add_row("delay per sample (ms)", f"{self.delay_ms:.3g}", f"{self.paper['delay_ms_per_sample']}")
        cmp.add_row("power (mW)", f"{self.power_mw:.3g} (dynamic only)", f"{self.paper['power_mw']} (total)")
        console.print(cmp)
        console.print("energy by component (uJ/sample): " + ", ".join(
            f"{k} {v:.3g}" for k, v in self.energy_uj.items() if k != "total"))
        console.print(f"step time: mean {self.step_ns['mean']:.0f} ns, max {self.step_ns['max']:.0f} ns "
                      f"(barrier {self.step_ns['barrier']:.0f} ns)")
        for a in self.assumptions:
            console.print(f"- {a}")


def _tile_xy(core: np.ndarray, chip) -> tuple[np.ndarray, np.ndarray]:
    core = np.asarray(core, np.int64)
    chip_id, local = np.divmod(core, chip.cores_per_chip)
    tile = local // chip.cores_per_tile
    x = chip_id * chip.mesh_tiles_ew + tile % chip.mesh_tiles_ew
    y = tile // chip.mesh_tiles_ew
    return x, y


def barrier_ns(tiles: int, costs) -> float:
    """Barrier time, linear from 1 tile (113 ns) to 32 tiles (465 ns), extrapolated beyond."""
    slope = (costs.barrier_max_ns - costs.barrier_min_ns) / (costs.barrier_max_tiles - 1)
    return costs.barrier_min_ns + slope * (max(tiles, 1) - 1)


def _active(spikes: np.ndarray, u: np.ndarray | None, v: np.ndarray | None) -> np.ndarray:
    """(B, T, n) bool: spiked, or u or v differs from the step before (zero before t = 0)."""
    act = spikes.astype(bool)
    for x in (u, v):
        if x is None:
            continue
        prev = np.concatenate([np.zeros_like(x[:, :1]), x[:, :-1]], axis=1)
        act |= x != prev
    return act


def estimate_energy(network: LoihiNetwork, core_map: CoreMap, spikes: dict[int, np.ndarray],
                    current: dict[int, np.ndarray] | None = None, voltage: dict[int, np.ndarray] | None = None,
                    input_note: str = "") -> EnergyEstimate:
    """The estimate for one emulation: ``spikes[i]`` (B, T, n_i) for every layer i (0 = input)."""
    from snncc.targets.loihi.mapping.projections import NetworkModel
    from snncc.targets.loihi.mapping.usage import pair_table

    chip = core_map.chip
    costs = chip.energy
    model = NetworkModel(network, chip)
    core_of = core_map.core_of_neuron()
    n_cores = core_map.n_cores
    pairs = pair_table(model, core_of, n_cores)
    batch, steps = spikes[0].shape[:2]
    n_global = model.n_global
    # per source neuron: synapses per destination core (S) and message cost to each core it reaches
    import scipy.sparse as sp

    syn = sp.csr_matrix((pairs.count.astype(np.float64), (pairs.src, pairs.dst_core)), shape=(n_global, n_cores))
    reach = syn.copy()
    reach.data[:] = 1.0
    src_core = np.zeros(n_global, np.int64)            # input neurons: injected at core 0's tile
    for i, cores in core_of.items():
        src_core[model.offset[i]:model.offset[i] + len(cores)] = cores
    coo = reach.tocoo()
    sx, sy = _tile_xy(src_core[coo.row], chip)
    dx_, dy_ = _tile_xy(coo.col, chip)
    hops_ew = np.abs(sx - dx_).astype(np.float64)
    hops_ns = np.abs(sy - dy_).astype(np.float64)
    in_tile = ((hops_ew + hops_ns) == 0).astype(np.float64)
    msg_pj = in_tile * costs.spike_in_tile_pj + hops_ew * costs.hop_ew_pj + hops_ns * costs.hop_ns_pj
    msg_ns = in_tile * costs.spike_in_tile_ns + hops_ew * costs.hop_ew_ns + hops_ns * costs.hop_ns_ns

    def per_source(values) -> np.ndarray:
        return np.bincount(coo.row, weights=values, minlength=n_global)

    src_msgs_ns_by_core = sp.csr_matrix((msg_ns, (coo.row, src_core[coo.row])), shape=(n_global, n_cores))
    per_src = {"messages_in_tile": per_source(in_tile), "hops_east_west": per_source(hops_ew),
               "hops_north_south": per_source(hops_ns), "routing_pj": per_source(msg_pj)}
    synops_per_src = np.asarray(syn.sum(axis=1)).ravel()

    totals = {k: 0.0 for k in ("synaptic_ops", "active_updates", "inactive_updates", "messages_in_tile",
                               "messages_between_tiles", "hops_east_west", "hops_north_south", "spikes",
                               "input_spikes")}
    routing_pj = 0.0
    step_time = np.zeros((batch, steps))
    n_on_chip = sum(len(c) for c in core_of.values())
    work = np.zeros((batch, steps, n_cores))
    for i in range(len(network.layers)):
        s = np.asarray(spikes[i], np.float64)                     # (B, T, n_i)
        gid = slice(int(model.offset[i]), int(model.offset[i] + network.layers[i].n))
        count = s.sum(axis=(0, 1))                                 # spikes per neuron over the batch
        totals["synaptic_ops"] += float(count @ synops_per_src[gid])
        for k in ("messages_in_tile", "hops_east_west", "hops_north_south"):
            totals[k] += float(count @ per_src[k][gid])
        routing_pj += float(count @ per_src["routing_pj"][gid])
        n_msgs = np.asarray(reach[gid].sum(axis=1)).ravel()
        totals["messages_between_tiles"] += float(count @ n_msgs) - float(count @ per_src["messages_in_tile"][gid])
        flat = s.reshape(batch * steps, -1)
        work += (flat @ syn[gid]).reshape(batch, steps, n_cores) * costs.synop_ns       # at the destination
        work += (flat @ src_msgs_ns_by_core[gid]).reshape(batch, steps, n_cores)        # sending cost at the source
        if i == 0:
            totals["input_spikes"] += float(count.sum())
            continue
        totals["spikes"] += float(count.sum())
        act = _active(spikes[i], None if current is None else current.get(i),
                      None if voltage is None else voltage.get(i))
        n_act = float(act.sum())
        totals["active_updates"] += n_act
        totals["inactive_updates"] += float(act.size) - n_act
        onehot = np.zeros((network.layers[i].n, n_cores))
        onehot[np.arange(network.layers[i].n), core_of[i]] = 1.0
        a = act.reshape(batch * steps, -1).astype(np.float64) @ onehot
        m = np.bincount(core_of[i], minlength=n_cores).astype(np.float64)
        work += (a * costs.update_active_ns + (m[None, :] - a) * costs.update_inactive_ns).reshape(batch, steps, n_cores)
    tiles_used = int(np.unique(np.stack(_tile_xy(np.arange(n_cores), chip), axis=1), axis=0).shape[0])
    bar = barrier_ns(tiles_used, costs)
    step_time = work.max(axis=2) + bar
    per_sample = {k: v / batch for k, v in totals.items()}
    energy_pj = {
        "synaptic_ops": per_sample["synaptic_ops"] * costs.synop_pj,
        "neuron_updates": per_sample["active_updates"] * costs.update_active_pj
        + per_sample["inactive_updates"] * costs.update_inactive_pj,
        "spike_routing": routing_pj / batch,
    }
    energy_uj = {k: v * 1e-6 for k, v in energy_pj.items()}
    energy_uj["total"] = sum(energy_uj.values())
    delay_ms = float(step_time.sum(axis=1).mean()) * 1e-6
    if n_on_chip != sum(lay.n for lay in network.layers[1:]):
        raise InternalError(f"the core map places {n_on_chip} neurons, the network has "
                            f"{sum(lay.n for lay in network.layers[1:])}", field="core map")
    return EnergyEstimate(
        label="ESTIMATE (not a measurement): Loihi 1 energy and delay from Davies 2018 Table 2",
        samples=int(batch), steps=int(steps), n_cores=n_cores, tiles_used=tiles_used,
        counts=per_sample, energy_uj=energy_uj, delay_ms=delay_ms,
        step_ns={"mean": float(step_time.mean()), "max": float(step_time.max()), "barrier": bar},
        power_mw=(energy_uj["total"] * 1e-6) / (delay_ms * 1e-3) * 1e3 if delay_ms > 0 else 0.0,
        input_note=input_note,
        assumptions=[
            f"geometry: {GEOMETRY}",
            f"costs: {costs.source}; dynamic energy only (no static, no x86/host power, no I/O)",
            "active update = spiked or u or v changed this step; every compartment is updated every step",
            "step time = slowest core's (synops + updates + sends) + barrier (linear 113..465 ns over 1..32 tiles)",
            "the paper's figures are measurements of the authors' 8-core mapping; this is an estimate",
        ],
    )


def merge(estimates: list[EnergyEstimate]) -> EnergyEstimate:
    """One estimate from estimates over disjoint batches (sample-weighted means, overall maxima)."""
    if len(estimates) == 1:
        return estimates[0]
    w = np.array([e.samples for e in estimates], np.float64)

    def mean(get):
        return float(np.dot(w, [get(e) for e in estimates]) / w.sum())

    first = estimates[0]
    counts = {k: mean(lambda e, k=k: e.counts[k]) for k in first.counts}
    energy = {k: mean(lambda e, k=k: e.energy_uj[k]) for k in first.energy_uj}
    delay = mean(lambda e: e.delay_ms)
    steps = {"mean": mean(lambda e: e.step_ns["mean"]), "max": max(e.step_ns["max"] for e in estimates),
             "barrier": first.step_ns["barrier"]}
    return EnergyEstimate(label=first.label, samples=int(w.sum()), steps=first.steps, n_cores=first.n_cores,
                          tiles_used=first.tiles_used, counts=counts, energy_uj=energy, delay_ms=delay,
                          step_ns=steps, power_mw=(energy["total"] * 1e-6) / (delay * 1e-3) * 1e3 if delay else 0.0,
                          input_note=first.input_note, assumptions=first.assumptions, paper=first.paper)


def emulate_and_estimate(network: LoihiNetwork, core_map: CoreMap, inputs: np.ndarray, input_note: str,
                         batch_size: int = 16, progress=None) -> EnergyEstimate:
    """Emulate ``inputs`` (B, T, C) batch by batch with every layer recorded; estimate and merge."""
    from snncc.targets.loihi.emulation.emulator import emulate

    parts = []
    for start in range(0, inputs.shape[0], batch_size):
        res = emulate(network, inputs[start:start + batch_size], record="all")
        parts.append(estimate_energy(network, core_map, res.spikes, res.current, res.voltage, input_note=input_note))
        if progress is not None:
            progress(min(start + batch_size, inputs.shape[0]))
    return merge(parts)
