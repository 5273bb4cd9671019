"""``profile`` of a Xylo artefact (``snncc compare``): the chip's limits, real time at the inputs' event rates,
NeuroBench.

resources   every design-rule quantity of the artefact's chip (``usage.chip_usage``: inputs, hidden and output
            neurons, expansion neurons, synaptic currents, fan-out, aliases) and the synapses used
real time   ``real_time.py``'s ESTIMATE from per-operation cycle costs at the event rates of these inputs (the
            expected load), the worst case (every channel and neuron active every step) beside it
energy      None: no published cost model gives this network's energy on the chip (none is invented)
NeuroBench  from the artefact's own emulation: synapses as stored (int8; each synaptic current's weight one
            synapse), the hidden neurons' events (up to 31 a step: graded, so their synaptic operations count
            as MACs) and the output events; footprint = every int8 weight spec.npz holds, and per neuron its
            16-bit membrane, 16-bit current per synaptic current, 16-bit threshold and 16-bit bias
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

CHUNK = 64
REGISTER_BYTES = 2


def _projections(spec: Any) -> list[Any]:
    from snncc.targets.kit.neurobench import Projection

    w_in = np.asarray(spec.weights_in)
    w_rec = np.asarray(spec.weights_rec)
    w_out = np.asarray(spec.weights_out)
    as_rows = (lambda w: w.reshape(w.shape[0], -1).T)      # (in, out[, syn]) -> (out x syn, in)
    return [Projection("input", "hidden", as_rows(w_in)), Projection("hidden", "hidden", as_rows(w_rec), 1),
            Projection("hidden_read", "output", as_rows(w_out))]


def _footprint(spec: Any) -> tuple[int, str]:
    weights = int(sum(np.asarray(getattr(spec, n)).size for n in ("weights_in", "weights_rec", "weights_out")))
    syns = int(np.asarray(spec.weights_in).shape[2]) if np.asarray(spec.weights_in).ndim == 3 else 1
    hidden, out = int(spec.n_hidden), int(spec.n_out)
    registers = hidden * (3 + syns) + out * 4
    return weights + REGISTER_BYTES * registers, (f"{weights:,} int8 weights; {registers:,} 16-bit neuron registers "
                                                  f"(membrane, {syns} synaptic current(s), threshold, bias)")


def profile_artefact(graph: Any, source: Path, inputs: np.ndarray,
                     progress: Callable[[int], None] | None = None) -> Any:
    """The ``Profile`` of the Xylo artefact at ``source`` on ``inputs`` (B, T, C) in the graph's input layout."""
    from snncc.targets.kit.neurobench import Tally, from_tally
    from snncc.targets.kit.profile import Profile, RealTime, Resource
    from snncc.targets.xylo.artefact.read import read_artefact
    from snncc.targets.xylo.chip import get_chip
    from snncc.targets.xylo.emulation.emulator import emulate
    from snncc.targets.xylo.emulation.run_artefact import artefact_inputs
    from snncc.targets.xylo.estimate.real_time import real_time
    from snncc.targets.xylo.estimate.usage import chip_usage, synapses

    written = read_artefact(source).runnable()
    spec = written.spec
    x = artefact_inputs(np.asarray(inputs), spec.n_in, None)
    b, t, c = x.shape
    pad, lag = written.input_pad, written.output_lag
    projections = _projections(spec)
    tally = Tally(projections, ["hidden", "output"])
    read_rows = int(np.asarray(spec.weights_out).shape[0])
    events = {"input": 0.0, "hidden": 0.0, "output": 0.0}
    for start in range(0, b, CHUNK):
        part = np.minimum(x[start:start + CHUNK], 255).astype(np.uint8)
        run = np.zeros((part.shape[0], t + max(pad, lag), c), np.uint8)
        run[:, pad:pad + t] = part
        res = emulate(spec, run, record=True)
        hidden = np.asarray(res.spikes)
        tally.add({"input": run, "hidden": hidden, "hidden_read": hidden[..., -read_rows:],
                   "output": np.asarray(res.output_spikes)})
        events["input"] += float(np.sum(part > 0))
        events["hidden"] += float(np.sum(hidden > 0))
        events["output"] += float(np.sum(np.asarray(res.output_spikes) > 0))
        if progress is not None:
            progress(int(part.shape[0]))
    rates = {"input": events["input"] / max(1, b * t * c),
             "hidden": events["hidden"] / max(1, b * (t + max(pad, lag)) * spec.n_hidden),
             "output": events["output"] / max(1, b * (t + max(pad, lag)) * spec.n_out)}
    rt = real_time(spec, float(spec.dt), rates).as_dict()
    chip = get_chip(written.chip)
    usage = chip_usage(spec, chip)
    resources = [Resource(name, float(v["used"]), float(v["limit"])) for name, v in usage.items()]
    resources.append(Resource("synapses", float(sum(synapses(spec).values()))))
    footprint, counted = _footprint(spec)
    figures = from_tally(tally, footprint, counted)
    basis = (f"ESTIMATE: {rt['note']}; {rt['cycles_expected']:,.0f} cycles a step expected at these inputs' event "
             f"rates, {rt['cycles_worst']:,.0f} at worst, {chip.name} at {rt['clock_hz'] / 1e6:g} MHz")
    timing = RealTime(bool(rt["real_time_expected"]), float(rt["margin_expected"]), float(rt["margin"]), basis)
    notes = [f"{chip.name}: no published energy cost model for this network; none is estimated"]
    return Profile("xylo", resources, figures, timing, None, notes)
