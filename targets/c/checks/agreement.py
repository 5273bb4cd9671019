"""``check`` and ``agree`` of a written C artefact: the float graph as trained against the artefact, stage by
stage (``kit.checks.CheckReport``), on the same samples.

    float       the model as trained (the reference)
    weights     the artefact's weights, thresholds, biases in float (``stages.py``)        cause weights
    decays      + the artefact's Q16 decays, in float                                    cause decays
    grid        the artefact's integer arithmetic with unbounded state (no clamp)        cause decays
    artefact    the artefact as written: the emulator, which the C equals bit for bit    cause saturation

The reset never changes on this target (a subtract-reset graph stays subtract) and it runs the IR's order
and delays: causes reset and timing are "—". The artefact is read from its files (``network.npz``, checked
against the manifest's hashes and against snn.c). With ``noise``: the float graph's own ceiling.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.targets.c.checks.stages import stage_graph

POSSIBLE = ("weights", "decays", "saturation")
LABELS = {"weights": "float, the artefact's weights, thresholds and biases",
          "decays": "float, + the artefact's Q16 decays",
          "grid": "integer state, unbounded (the artefact's arithmetic without the int32 clamp)",
          "artefact": "the artefact as written (emulator = the C, bit for bit)"}
CHUNK = 64


def check_written(graph, written, x: np.ndarray, labels: np.ndarray | None, what: str, *,  # noqa: ANN001
                  noise: float | None = None, progress=None):
    """The ``CheckReport`` of ``written`` (``artefact.written.WrittenC``) on ``x`` (N, T, C) (module doc)."""
    from snncc.ir import liveness
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.kit.agreement import argmax_agreement, chunk_size, count_correlation
    from snncc.targets.kit.checks import accuracy_pair, ceiling_record, report_from, stage
    from snncc.targets.kit.reference import float_counts, noise_ceiling

    net = written.network
    out = net.populations[net.output].name
    names = [p.name for p in net.populations]
    graphs = {"weights": stage_graph(graph, net, decays=False), "decays": stage_graph(graph, net, decays=True)}
    x = np.asarray(x)
    n, t = int(x.shape[0]), int(x.shape[1])
    counts: dict[str, list[np.ndarray]] = {k: [] for k in ("float", "weights", "decays", "grid", "artefact")}
    saturated = {p: 0 for p in names}
    float_tally, c_tally = liveness.Tally(), liveness.Tally()
    step = chunk_size(sum(p.n for p in net.populations), t, CHUNK)
    for start in range(0, n, step):
        part = x[start:start + step]
        from snncc.targets.kit.reference import float_spikes

        ref = float_spikes(graph, part, names)
        float_tally.add(ref)
        counts["float"].append(ref[out].sum(axis=1, dtype=np.int64))
        for key, g in graphs.items():
            counts[key].append(float_counts(g, part, out))
        counts["grid"].append(emulate_network(net, part, saturate=False).counts)
        run = emulate_network(net, part, populations=tuple(names))
        for p, v in run.saturated.items():
            saturated[p] += v
        c_tally.add(run.spikes)
        counts["artefact"].append(run.counts)
        if progress is not None:
            progress(int(part.shape[0]))
    c = {k: np.concatenate(v) if v else np.zeros((0, net.outputs), np.int64) for k, v in counts.items()}
    main = argmax_agreement(c["float"], c["artefact"])
    stages = [stage(k, LABELS[k], cause, argmax_agreement(c["float"], c[k]),
                    None if labels is None else float(np.mean(np.argmax(c[k], axis=1) == labels)))
              for k, cause in (("weights", "weights"), ("decays", "decays"), ("grid", "decays"),
                               ("artefact", "saturation"))]
    ceiling = None if not noise else ceiling_record(noise_ceiling(graph, x, c["float"], noise), noise)
    refractory = {p.name: p.refractory for p in net.populations}
    f_act = float_tally.activity(refractory)
    c_act = c_tally.activity(refractory)
    acc = None if labels is None else accuracy_pair(np.argmax(c["float"], axis=1), np.argmax(c["artefact"], axis=1),
                                                    labels)
    details: dict[str, Any] = {"artefact_sha256": written.sha256, "rule": net.rule, "saturated": saturated,
                               "selection": written.manifest.get("selection")}
    lines = [f"C artefact {written.sha256[:16]}..., rule {net.rule}; saturated state updates: "
             + (", ".join(f"{k} {v}" for k, v in saturated.items()) if any(saturated.values()) else "none")]
    notes = []
    if labels is None:
        notes.append("agreement with the float graph as trained; random inputs say nothing of accuracy on real data")
    if t != net.steps:
        notes.append(f"the inputs have {t} steps; the artefact's samples last {net.steps} (the emulator ran the "
                     "inputs' length)")
    return report_from("c", inputs=what, samples=n, steps=t, artefact=main,
                       count_correlation=count_correlation(c["artefact"], c["float"]), stages=stages,
                       possible=POSSIBLE, accuracy=acc, ceiling=ceiling,
                       liveness={"float": liveness.as_dicts(f_act), "c": liveness.as_dicts(c_act)},
                       flagged=liveness.flagged(f_act, "in float") + liveness.flagged(c_act, "in the C artefact"),
                       notes=notes, details=details, detail_lines=lines)


def check_artefact(graph, artefact, x, labels, what, *, noise=None, progress=None):  # noqa: ANN001
    """``check_written`` of the artefact at path ``artefact`` (opened and checked)."""
    from snncc.targets.c.artefact.written import open_artefact

    return check_written(graph, open_artefact(artefact), x, labels, what, noise=noise, progress=progress)


__all__ = ["check_written", "check_artefact", "POSSIBLE", "LABELS"]
