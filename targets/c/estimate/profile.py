"""``profile`` of a C artefact (``snncc compare``): ``kit.profile.Profile``, filled from the artefact as written.

resources   flash (snn.o's text for a Cortex-M4 at -Os where arm-none-eabi-gcc is installed, else the constant
            data of snn.c), RAM (sizeof(snn_state_t)), neurons and nonzero synapses, against the part the artefact
            was compiled for (``--mcu``)
real time   instructions per step counted in QEMU on the inputs (the Cortex-M4 build, ``-icount shift=0``), times the
            assumed CPI, against the part's clock x dt: margin = dt / time per step (an ESTIMATE; ``realtime.py``);
            None where arm-none-eabi-gcc or qemu-system-arm is missing
energy      the part's datasheet run current per MHz x 3 V x time per step x steps per sample (an ESTIMATE with its
            source); delay per sample = steps x time per step
NeuroBench  the synapses as stored (int weights: a weight rounded to 0 is zero), the emulator's spikes on the inputs
            (= the C's); footprint = the constant data (weights and per-neuron constants) plus the state, in bytes
"""

from __future__ import annotations

import numpy as np

from snncc.targets.kit import SnnccError


def profile_artefact(graph, artefact, inputs: np.ndarray, progress=None):   # noqa: ANN001
    """The ``Profile`` of the C artefact at ``artefact`` (compiled from ``graph``) on ``inputs`` (B, T, C)."""
    from snncc.targets.c.artefact.written import open_artefact
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.emulation.run_artefact import artefact_inputs
    from snncc.targets.c.estimate.parts import DEFAULT_PART, PARTS
    from snncc.targets.c.estimate.report import estimate_artefact
    from snncc.targets.kit.agreement import chunk_size
    from snncc.targets.kit.neurobench import Projection, Tally, from_tally
    from snncc.targets.kit.profile import EnergyEstimate, Profile, RealTime, Resource

    written = open_artefact(artefact)
    net = written.network
    x, _ = artefact_inputs(written, np.asarray(inputs), None)
    if not net.populations:
        raise SnnccError("NeuroBench's spiking metrics need spiking populations; this artefact has none", field="model")
    key = written.manifest.get("part", {}).get("key") or DEFAULT_PART
    part = PARTS[key]
    usage = estimate_artefact(artefact, x, f"{x.shape[0]} samples of the comparison's inputs", key)
    fitted = usage.fit
    synapses = int(sum(np.count_nonzero(q.weights) for q in net.projections))
    resources = [Resource(f"flash ({fitted['flash_counted']})", fitted["flash_bytes"], part["flash_bytes"], "B"),
                 Resource("RAM (sizeof snn_state_t)", fitted["ram_bytes"], part["ram_bytes"], "B"),
                 Resource("neurons", sum(p.n for p in net.populations)), Resource("synapses (nonzero)", synapses)]
    real_time = energy = None
    notes = [f"part: {part['name']} ({part['source']})"] + list(usage.notes)
    t = usage.timing
    if t is not None:
        budget = t["cycle_budget_per_step"]
        real_time = RealTime(bool(t["real_time"]), budget / max(t["cycles_per_step"], 1e-9),
                             budget / max(t["worst_step_cycles"], 1e-9),
                             f"ESTIMATE: {t['instructions_per_step']:.0f} instructions per step counted in QEMU "
                             f"(Cortex-M4 build) x CPI {t['cpi_assumed']} (assumed) at {part['clock_hz'] / 1e6:g} MHz")
        energy = EnergyEstimate(1e6 * t["energy_per_sample_j"], 1e3 * t["time_per_step_s"] * t["steps_per_sample"],
                                f"{part['run_ua_per_mhz']:g} uA/MHz x 3 V x time per step ({part['source']}); "
                                f"CPI {t['cpi_assumed']} assumed")
    names = {-1: net.names.get("input") or "input", **{i: p.name for i, p in enumerate(net.populations)}}
    projections = [Projection(names[q.source], f"c.w{k}", q.weights.T.astype(np.float64), int(q.delay))
                   for k, q in enumerate(net.projections)]
    pops = [p.name for p in net.populations]
    tally = Tally(projections, pops)
    step = chunk_size(sum(p.n for p in net.populations), int(x.shape[1]), 64)
    for start in range(0, x.shape[0], step):
        part_x = x[start:start + step]
        run = emulate_network(net, part_x, populations=tuple(pops))
        tally.add({names[-1]: part_x, **run.spikes})
        if progress is not None:
            progress(int(part_x.shape[0]))
    memory = usage.memory
    footprint = int(memory["flash_data_bytes"] + memory["ram_state_bytes"])
    figures = from_tally(tally, footprint, "snn.c's constant data (weights, exponents, thresholds, decays, biases) plus "
                                           "sizeof(snn_state_t)")
    return Profile("c", resources, figures, real_time, energy, notes)


__all__ = ["profile_artefact"]
