"""``snncc check --target loihi --data``: what the written bundle costs on a labelled data set, and why.

Runs on the same inputs, each a stage between the model and the bundle:
  (a) the float model as trained (IR reference of the model file, its own reset)
  (r) the float model with reset to zero (only when --allow-reset-change replaced a subtract reset)
  (b) the IR in the order Loihi runs, float (timing change only, e.g. the paper's export order)
  (c) the IR with the quantized weights, thresholds and decay constants, float
  (d) the bundle as written, read from its file and run in the bit-exact emulator
plus (d') the bundle with wide registers (no overflow) when any overflow occurred, and, for a
relayed bundle, (d0) the same network without relays (the loss "relays" = acc(d0) - acc(d)).
Loss split: reset = acc(a) - acc(r); timing = acc(r) - acc(b); quantization = acc(b) - acc(c);
integer_truncation = acc(c) - acc(d'); overflow = acc(d') - acc(d) (relayed: measured on (d0));
total = acc(a) - acc(d). Stages (r), (b), (c) exist only inside the compiler: they are re-derived
from the model with the bundle's recorded options (``written.py``); when that does not reproduce
the bundle, only (a) and (d) are measured and the record says why.

Prediction agreements follow ``snncc.measure.agreement``'s rule (samples whose float output has no
single winner are left out and counted); liveness (``snncc.ir.liveness``) is measured for every
population in float (a) and on the bundle (d).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.simulate import simulate

CHUNK = 64
STAGES = ("float_trained", "ir_reset_changed", "ir_loihi_order", "ir_quantized", "emulator_without_relays",
          "emulator_wide", "emulator")


@dataclass
class CheckRecord:
    target: str
    samples: int
    steps: int
    timing: str
    scale_rule: str
    scale_reason: str
    accuracy: dict[str, float]                 # stage -> accuracy (only the stages measured)
    loss_points: dict[str, float]              # reset, timing, quantization, integer_truncation, overflow, [relays], total
    spike_agreement: dict[str, dict[str, float | None]]   # comparison -> layer -> share of equal entries (None: both silent)
    prediction_agreement: dict[str, dict[str, Any]]       # comparison -> ArgmaxAgreement (decided rule, 95 % interval)
    overflow: dict[str, int]
    mode: str = "batch"
    notes: list[str] = field(default_factory=list)
    reset_changed: bool = False                # --allow-reset-change replaced a subtract reset
    liveness: dict[str, Any] = field(default_factory=dict)   # "float" / "loihi": population -> activity
    flagged: list[str] = field(default_factory=list)         # silent or saturated populations
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def render_text(self, console) -> None:
        from snncc.measure.agreement import ArgmaxAgreement

        a, l = self.accuracy, self.loss_points
        say = lambda text: console.print(text, markup=False, highlight=False, soft_wrap=True)  # noqa: E731
        say(f"snncc check: {self.target} on {self.samples} samples x {self.steps} steps "
            f"(timing '{self.timing}', scale '{self.scale_rule}', {self.mode} mode)")
        labels = {"float_trained": "(a) float model as trained", "ir_reset_changed": "(r) reset to zero instead, float",
                  "ir_loihi_order": "(b) IR in Loihi order, float", "ir_quantized": "(c) IR with quantized parameters, float",
                  "emulator_without_relays": "(d0) the network without relays, emulator",
                  "emulator": "(d) the bundle as written, emulator (bit-exact)"}
        for key, label in labels.items():
            if key in a:
                say(f"  {label:<50} accuracy {100 * a[key]:6.2f} %")
        say("  loss (points) from: " + ", ".join(f"{k} {v:+.2f}" for k, v in l.items()))
        for name, per_layer in self.spike_agreement.items():
            say(f"  spike agreement {name}: " + ", ".join(
                f"{k} {'undefined (silent)' if v is None else f'{100 * v:.2f}%'}" for k, v in per_layer.items()))
        for name, agreement in self.prediction_agreement.items():
            say(f"  prediction agreement {name}: {ArgmaxAgreement(**agreement).text()}")
        say(f"  overflow events: {self.overflow}")
        for line in self.flagged:
            say(f"  liveness: {line}")
        for line in self.warnings:
            say(f"  warning: {line}")
        for note in self.notes:
            say(f"  note: {note}")


def _ir_run(graph: Graph, x: np.ndarray, names: list[str], cut=None) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(output spike counts (B, classes), population spikes) of the float IR; ``cut`` maps the population
    spikes of a lowering stage to the model's neurons (``WrittenBundle.cut``: replicated populations)."""
    from snncc.threads import one_thread

    with one_thread():
        res = simulate(graph, x, record="spikes")
    spikes = {n: np.asarray(res.spikes[n]).astype(np.uint8) for n in names}
    if cut is not None:
        spikes = cut(spikes)
    return spikes[names[-1]].sum(axis=1, dtype=np.int64), spikes


def _layer_agreement(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> dict[str, float | None]:
    """Share of equal spike entries per layer; None where both are silent (nothing to agree on)."""
    return {k: None if not a[k].any() and not b[k].any() else float(np.mean(a[k] == b[k])) for k in a}


def check_bundle(graph: Graph, bundle, inputs: np.ndarray, labels: np.ndarray, options: dict[str, Any],
                 progress: Callable[[int], None] | None = None) -> CheckRecord:
    """Measure the written ``bundle`` (``written.WrittenBundle``) against ``graph`` on ``inputs`` (N, T, C)
    0/1 with ``labels`` (N,); ``progress(n)`` after each chunk. Options: mode ("batch" | "stream"),
    gap, data (the data file, for messages), synthetic."""
    from snncc.ir import liveness
    from snncc.measure.agreement import argmax_agreement
    from snncc.targets.loihi.checks.exactness import lead_steps, loihi_spikes
    from snncc.targets.loihi.emulation.emulator import check_inputs, emulate, pad

    net = bundle.network
    x_all = check_inputs(inputs, net.input_width, source=options.get("data"))
    labels = np.asarray(labels).reshape(-1)
    if labels.shape[0] != x_all.shape[0]:
        raise SnnccError(f"{labels.shape[0]} labels for {x_all.shape[0]} samples", file=options.get("data"), field="labels")
    n, steps, _ = x_all.shape
    names = bundle.populations
    lowered = bundle.lowered
    mode, gap = options.get("mode", "batch"), int(options.get("gap", 100))
    relayed = lowered is not None and "relayed_layer_index" in net.metadata
    counts: dict[str, list[np.ndarray]] = {k: [] for k in STAGES}
    compare = {"emulator_vs_trained": ("emulator", "float_trained")}
    if lowered is not None:
        compare.update({"emulator_vs_quantized_ir": ("emulator", "ir_quantized"),
                        "loihi_order_vs_trained": ("ir_loihi_order", "float_trained")})
    agree_sum = {k: {nm: [0.0, 0] for nm in names} for k in compare}
    overflow = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    float_tally, loihi_tally = liveness.Tally(), liveness.Tally()
    wide_needed = False
    chunks = []
    from snncc.measure.agreement import chunk_size

    chunk = chunk_size(sum(net.layers[bundle.layer_of[p]].model_n for p in names), steps, CHUNK)
    for start in range(0, n, chunk):
        x = x_all[start:start + chunk]
        runs: dict[str, tuple[np.ndarray, dict[str, np.ndarray]]] = {"float_trained": _ir_run(graph, x, names)}
        if lowered is not None:
            order = lowered.order
            runs["ir_loihi_order"] = (_ir_run(order, x, names, bundle.cut) if order is not lowered.trained
                                      else runs["float_trained"])
            if lowered.deployed is not None:
                runs["ir_reset_changed"] = (runs["ir_loihi_order"] if order is lowered.deployed
                                            else _ir_run(lowered.deployed, x, names, bundle.cut))
            else:
                runs["ir_reset_changed"] = runs["float_trained"]
            runs["ir_quantized"] = _ir_run(lowered.quantized, x, names, bundle.cut)
        s_d, res = bundle.run(x, mode=mode, gap=gap)
        runs["emulator"] = (s_d[names[-1]].sum(axis=1, dtype=np.int64), s_d)
        if relayed:
            trec = lowered.timing_record
            kw = {"mode": "stream", "gap": gap} if mode == "stream" else {}
            plain = emulate(lowered.network, pad(x, lead_steps(trec.shifts, trec.output_shift)), record="all", **kw)
            s_0 = bundle.cut(loihi_spikes(plain, lowered.network, lowered.layers, trec.shifts, steps))
            runs["emulator_without_relays"] = (s_0[names[-1]].sum(axis=1, dtype=np.int64), s_0)
            res_over = plain.overflow
        else:
            res_over = res.overflow
        for k, v in res_over.items():
            overflow[k] += v
        wide_needed = wide_needed or any(res_over.values())
        chunks.append(x)
        for key, (c, _) in runs.items():
            counts[key].append(c)
        float_tally.add(runs["float_trained"][1])
        loihi_tally.add(s_d)
        w = x.shape[0]
        for comp, (got, want) in compare.items():
            for nm in names:
                a, b = runs[got][1][nm], runs[want][1][nm]
                if a.any() or b.any():
                    agree_sum[comp][nm][0] += float(np.mean(a == b)) * w
                    agree_sum[comp][nm][1] += w
        if progress is not None:
            progress(w)
    base = "emulator_without_relays" if relayed else "emulator"
    if wide_needed:
        for x in chunks:
            if relayed:
                trec = lowered.timing_record
                kw = {"mode": "stream", "gap": gap} if mode == "stream" else {}
                r = emulate(lowered.network, pad(x, lead_steps(trec.shifts, trec.output_shift)), wide=True, **kw)
                out = r.output_spikes[:, trec.output_shift:trec.output_shift + steps]
            else:
                out = bundle.run_wide(x, mode=mode, gap=gap)
            counts["emulator_wide"].append(out.sum(axis=1, dtype=np.int64))
    else:
        counts["emulator_wide"] = counts[base]
    c = {k: np.concatenate(v) for k, v in counts.items() if v}
    pred = {k: np.argmax(v, axis=1) for k, v in c.items()}
    acc = {k: float(np.mean(v == labels)) for k, v in pred.items()}
    if lowered is not None:
        loss = {
            "reset": 100 * (acc["float_trained"] - acc["ir_reset_changed"]),
            "timing": 100 * (acc["ir_reset_changed"] - acc["ir_loihi_order"]),
            "quantization": 100 * (acc["ir_loihi_order"] - acc["ir_quantized"]),
            "integer_truncation": 100 * (acc["ir_quantized"] - acc["emulator_wide"]),
            "overflow": 100 * (acc["emulator_wide"] - acc[base]),
        }
        if relayed:
            loss["relays"] = 100 * (acc["emulator_without_relays"] - acc["emulator"])
    else:
        loss = {}
    loss["total"] = 100 * (acc["float_trained"] - acc["emulator"])
    shown = [k for k in ("float_trained", "ir_reset_changed", "ir_loihi_order", "ir_quantized",
                         "emulator_without_relays", "emulator") if k in acc]
    notes = []
    meta = net.metadata
    changes = list((meta.get("timing") or {}).get("changes") or [])
    notes += [f"timing: {ch}" for ch in changes]
    if bundle.stages_note:
        notes.append(bundle.stages_note)
    if relayed:
        from snncc.targets.loihi.mapping.relays import RelayPlan

        notes += RelayPlan(records=list(meta.get("fan_in_relays") or []), index=list(meta["relayed_layer_index"]),
                           shift=[]).notes()
    if steps != bundle.steps:
        notes.append(f"the inputs have {steps} steps; the bundle's tSample is for {bundle.steps} (the emulator runs "
                     "the inputs' length)")
    if options.get("synthetic"):
        notes.append("the data set is synthetic: these accuracies are not the paper's")
    f_act = float_tally.activity(liveness.graph_refractory(graph))
    l_act = loihi_tally.activity({nm: int(net.layers[bundle.layer_of[nm]].ref_delay) for nm in names})
    warning = liveness.float_silence_warning(graph, x_all[:chunk], f_act, f"the first {min(chunk, n)} of these samples")
    quant = meta.get("quantization") or {}
    prediction = {
        "emulator_vs_trained": argmax_agreement(c["float_trained"], c["emulator"]).as_dict(),
        **({"emulator_vs_quantized_ir": argmax_agreement(c["ir_quantized"], c["emulator"]).as_dict(),
            "loihi_order_vs_trained": argmax_agreement(c["float_trained"], c["ir_loihi_order"]).as_dict()}
           if lowered is not None else {}),
        **({"relayed_vs_emulator": argmax_agreement(c["emulator_without_relays"], c["emulator"]).as_dict()}
           if relayed else {}),
    }
    return CheckRecord(
        target="loihi", samples=n, steps=steps, timing=str(meta.get("timing", "unknown")) if isinstance(
            meta.get("timing"), str) else str((meta.get("timing") or {}).get("mode", "unknown")),
        scale_rule=str(quant.get("rule", "unknown")), scale_reason=str(quant.get("reason", "not recorded")),
        accuracy={k: acc[k] for k in shown},
        loss_points=loss,
        spike_agreement={k: {nm: (s / w if w else None) for nm, (s, w) in d.items()} for k, d in agree_sum.items()},
        prediction_agreement=prediction,
        overflow=overflow, mode=mode, notes=notes, reset_changed=lowered is not None and lowered.deployed is not None,
        liveness={"float": liveness.as_dicts(f_act), "loihi": liveness.as_dicts(l_act)},
        flagged=liveness.flagged(f_act, "in float") + liveness.flagged(l_act, "on Loihi (the bundle)"),
        warnings=[warning] if warning else [],
    )


def check_model(graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: dict[str, Any],
                progress: Callable[[int], None] | None = None) -> CheckRecord:
    """``check_bundle`` on the bundle ``compile`` would write for ``graph`` with ``options`` (written to a
    temporary directory and read back: the measured network is the file's)."""
    from snncc.targets.kit.measured import compiled as compiled_artefact
    from snncc.targets import get_target
    from snncc.targets.loihi.checks.written import open_bundle

    with compiled_artefact(get_target("loihi"), graph, options) as path:
        return check_bundle(graph, open_bundle(path, graph), inputs, labels, options, progress)
