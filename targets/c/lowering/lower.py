"""``lower``: IR graph -> float structure -> the integer network (rule given or measured) -> the C artefact,
checked before it is returned.

The check: ``network.npz`` as written is read back and must equal the lowered network; ``snn.c`` and ``snn.h``
regenerated from what was read must be byte-identical to the files written (so the C is that network's); the
read-back network's emulation must equal the lowered network's, every population's spikes, current and voltage,
on seeded samples. That the C equals the emulator bit for bit is proved by the test suite (host gcc and the
Cortex-M4 build in QEMU, on random and real graphs), and ``snncc run --backend host|qemu`` repeats it on any
inputs; compiling needs no C compiler.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.c.options import COptions, DECAY_BITS, DEFAULT_PART, THRESHOLD_BITS, VALIDATION_SAMPLES

ARITHMETIC = {
    "state": "int32 current I and voltage V per neuron in units of 2**-F of the model's units; F per population puts "
             f"its largest threshold in [2**{THRESHOLD_BITS}, 2**{THRESHOLD_BITS + 1}) units",
    "weights": "int8 (rules per-layer, per-neuron) or int16 (per-layer-16, per-neuron-16), scaled by 2**e state units, "
               "e >= 0 per projection (per-layer) or per projection and target neuron (per-neuron); rounded to nearest",
    "decays": f"alpha, beta as Q{DECAY_BITS} multipliers; a * x rounded half up: "
              f"floor((a * x + 2**{DECAY_BITS - 1}) / 2**{DECAY_BITS}), with floor written portably (no right shift "
              "of a negative value)",
    "saturation": "I and V computed exactly in 64 bits each step, then clamped to [-2**31, 2**31 - 1]; output counts "
                  "saturate at 65535; accumulators cannot overflow (checked at compile)",
    "order": "the IR's: populations in the schedule of zero-delay edges; I, then V, then refractory hold, then spikes "
             "(threshold subtracted per spike, at most max_spikes), then reset (zero or subtract, as the graph states)",
    "delivery": "event-driven: each source keeps a ring of event lists (neurons that spiked, with counts) as long as "
                "its longest delay; a projection adds the fan-out rows of the events d steps back",
}


def _validate(art, net, rule_text: str) -> str:   # noqa: ANN001
    from snncc.targets.c.artefact import csource
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.c.lowering.network import network_arrays, read_network
    from snncc.targets.kit.agreement import random_inputs
    from snncc.targets.kit import InternalError

    back = read_network(art.files["network.npz"], source="network.npz")
    mine, theirs = network_arrays(net), network_arrays(back)
    if mine.keys() != theirs.keys() or any(not np.array_equal(mine[k], theirs[k]) for k in mine):
        raise InternalError("network.npz read back differs from the lowered network")
    meta = {"model": rule_text}
    if csource.source(back, meta).encode() != art.files["snn.c"] or \
            csource.header(back, meta).encode() != art.files["snn.h"]:
        raise InternalError("snn.c regenerated from network.npz differs from the snn.c written")
    x = random_inputs(VALIDATION_SAMPLES, min(net.steps, 256), net.inputs, 0.1, 11)
    a, b = emulate_network(net, x, record=True), emulate_network(back, x, record=True)
    for p in net.populations:
        for kind in ("spikes", "current", "voltage"):
            if not np.array_equal(getattr(a, kind)[p.name], getattr(b, kind)[p.name]):
                raise InternalError(f"the re-read network's {kind} of {p.name} differs")
    return (f"network.npz read back equals the lowered network; snn.c and snn.h regenerated from it are "
            f"byte-identical; its emulation equals the lowered network's on {VALIDATION_SAMPLES} seeded samples "
            f"(every population's spikes, current, voltage)")


def lower_network(graph, options: COptions):   # noqa: ANN001
    """(the integer network, the rule's ``Selection``, steps, the time-base rule) of ``graph``; refusals name the
    model file."""
    from snncc.targets.c.estimate.parts import PARTS
    from snncc.targets.c.lowering.choose import lowered_network
    from snncc.targets.c.lowering.structure import structure
    from snncc.targets.kit.timebase import sample_steps

    steps, steps_rule = sample_steps(graph, options.time_steps)
    part = PARTS[options.mcu or DEFAULT_PART]
    try:
        st = structure(graph)
        net, selection = lowered_network(st, graph, options.rule or "auto", steps, options.seed,
                                         part["flash_bytes"], part["name"])
    except SnnccError as err:
        raise (err.with_file(options.source) if options.source else err) from None
    return net, selection, steps, steps_rule


def package_network(graph, net, options: COptions, selection, steps_rule: str, *,  # noqa: ANN001
                    extra: dict[str, Any] | None = None, notes: list[str] | None = None):
    """The checked ``CArtefact`` of ``net`` (module doc); ``extra``: further manifest entries (fine-tuning)."""
    from snncc.targets.c.artefact import csource
    from snncc.targets.c.artefact.package import CArtefact, artefact_files, base_manifest
    from snncc.targets.c.artefact.readme import readme
    from snncc.targets.c.estimate.memory import fit, memory_record
    from snncc.targets.c.estimate.parts import PARTS
    from snncc.targets.kit.inputs import graph_layout

    layout = graph_layout(graph)
    part_key = options.mcu or DEFAULT_PART
    memory = memory_record(net, csource.source(net, {}))
    part = {"key": part_key, **fit(memory, PARTS[part_key])}
    manifest = base_manifest(
        net, graph, options.source, {"rule": net.rule, **ARITHMETIC}, selection.as_dict(),
        {"steps": net.steps, "rule": steps_rule, "dt": float(graph.dt)}, memory, part, {}, {
            "width": layout.width, "input_copies": layout.copies, "base_inputs": layout.base,
            "input_shape": list(layout.frame) if layout.frame else None})
    from snncc.targets.kit.inputs import to_jsonable

    manifest.update(to_jsonable(extra or {}))
    manifest["validation"] = {"emulator": "pending", "c": (
        "the C equals the emulator bit for bit: proved by snncc's test suite (host gcc; Cortex-M4 in QEMU) and "
        "repeated by `snncc run DIR --target c --backend host|qemu`; compiling needed no C compiler")}
    files, full = artefact_files(net, manifest, readme(net, manifest))
    text = full["source"].get("file") or full["model"]["graph_sha256"]
    manifest["validation"]["emulator"] = _validate(CArtefact(files, full, net), net, text)
    files, full = artefact_files(net, manifest, readme(net, manifest))
    return CArtefact(files, full, net, list(notes or []))


def lower_artefact(graph, options: COptions, *, progress=None):   # noqa: ANN001
    """The ``CArtefact`` of ``graph`` (module doc)."""
    report = progress or (lambda done, total, phase: None)
    report(0, 2, "structure and weight rules")
    net, selection, _, steps_rule = lower_network(graph, options)
    report(1, 2, "writing and checking the C")
    art = package_network(graph, net, options, selection, steps_rule)
    report(2, 2, "done")
    return art


__all__ = ["lower_artefact", "lower_network", "package_network", "ARITHMETIC"]
