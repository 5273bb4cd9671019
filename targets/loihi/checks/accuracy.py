"""``snncc check --target loihi``: what deploying on Loihi costs, on a data set, and why.

Four runs on the same inputs (five when the reset changes):
  (a) the float model as trained (IR reference of the original graph)
  (r) the float model with reset to zero (only when --allow-reset-change replaced a subtract reset)
  (b) the IR in the order Loihi runs, float (timing change only, e.g. the paper's export order)
  (c) the IR with the quantized weights, thresholds and decay constants, float
  (d) the bit-exact emulator of the bundle (integer, truncating decays, wrap/clip)
plus (d') the emulator without overflow (wide registers) when any overflow occurred, and (e) the
relayed bundle when a layer's fan-in needs relays (``relays.py``; loss "relays" = acc(d) - acc(e)).
Loss split: reset = acc(a) - acc(r); timing = acc(r) - acc(b); quantization = acc(b) - acc(c) + acc(c) - acc(d'),
i.e. parameters plus integer truncation; overflow = acc(d') - acc(d).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Callable

import numpy as np

from snncc.errors import SnnccError
from snncc.ir.graph import Graph
from snncc.ir.simulate import simulate

CHUNK = 64


@dataclass
class CheckRecord:
    target: str
    samples: int
    steps: int
    timing: str
    scale_rule: str
    scale_reason: str
    accuracy: dict[str, float]                 # float_trained, ir_reset_changed, ir_loihi_order, ir_quantized, emulator
    loss_points: dict[str, float]              # reset, timing, quantization (params), truncation, overflow, total
    spike_agreement: dict[str, dict[str, float]]   # comparison -> layer -> fraction of equal entries
    prediction_agreement: dict[str, float]
    overflow: dict[str, int]
    mode: str = "batch"
    notes: list[str] = field(default_factory=list)
    reset_changed: bool = False                # --allow-reset-change replaced a subtract reset

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def render_text(self, console) -> None:
        a, l = self.accuracy, self.loss_points
        console.print(f"[bold]snncc check: {self.target}[/bold] on {self.samples} samples x {self.steps} steps "
                      f"(timing '{self.timing}', scale '{self.scale_rule}', {self.mode} mode)")
        rows = [("(a) float model as trained", "float_trained")] + (
            [("(r) reset to zero instead, float", "ir_reset_changed")] if self.reset_changed else []) + [
                ("(b) IR in Loihi order, float", "ir_loihi_order"),
                ("(c) IR with quantized parameters, float", "ir_quantized"), ("(d) Loihi emulator (bit-exact)", "emulator")] + (
            [("(e) relayed bundle (fan-in relays), emulator", "relayed")] if "relayed" in a else [])
        for label, key in rows:
            console.print(f"  {label:<42} accuracy {100 * a[key]:6.2f} %")
        console.print("  loss (points) from: " + ", ".join(f"{k} {v:+.2f}" for k, v in l.items()))
        for name, per_layer in self.spike_agreement.items():
            console.print(f"  spike agreement {name}: " + ", ".join(f"{k} {100 * v:.2f}%" for k, v in per_layer.items()))
        console.print("  prediction agreement: " + ", ".join(f"{k} {100 * v:.1f}%" for k, v in self.prediction_agreement.items()))
        console.print(f"  overflow events: {self.overflow}")
        for note in self.notes:
            console.print(f"  note: {note}")


def _ir_run(graph: Graph, x: np.ndarray, names: list[str]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    from snncc.threads import one_thread

    with one_thread():
        res = simulate(graph, x, record="spikes")
    return res.prediction.numpy(), {n: res.spikes[n].numpy().astype(np.uint8) for n in names}


def _relays(network):
    """(relayed network, plan) when a layer's fan-in needs relays, else (None, None)."""
    from snncc.targets.loihi.mapping.relays import needs_relays, relay_network

    if not needs_relays(network):
        return None, None
    return relay_network(network)


def check_model(graph: Graph, inputs: np.ndarray, labels: np.ndarray, options: dict[str, Any],
                progress: Callable[[int], None] | None = None) -> CheckRecord:
    """Run (a)-(d) over ``inputs`` (N, T, C) 0/1 with ``labels`` (N,); ``progress(n)`` after each chunk."""
    from snncc.targets.loihi import lower_model
    from snncc.targets.loihi.emulation.emulator import check_inputs, emulate
    from snncc.targets.loihi.checks.exactness import lead_steps, loihi_spikes, pad

    lowered = lower_model(graph, dict(options, t_sample=options.get("t_sample") or np.asarray(inputs).shape[1]))
    net = lowered.network
    x_all = check_inputs(inputs, net.input_width, source=options.get("data"))
    labels = np.asarray(labels).reshape(-1)
    if labels.shape[0] != x_all.shape[0]:
        raise SnnccError(f"{labels.shape[0]} labels for {x_all.shape[0]} samples", file=options.get("data"), field="labels")
    n, steps, _ = x_all.shape
    names = [c.lif for c in lowered.layers]
    shift = lowered.timing_record.output_shift
    lead = lead_steps(lowered.timing_record.shifts, shift)
    mode = options.get("mode", "batch")
    relayed, plan = _relays(net)
    preds = {k: [] for k in ("float_trained", "ir_reset_changed", "ir_loihi_order", "ir_quantized", "emulator",
                             "emulator_wide", "relayed")}
    agree_sum = {k: {nm: 0.0 for nm in names} for k in
                 ("emulator_vs_trained", "emulator_vs_quantized_ir", "loihi_order_vs_trained")}
    overflow = {"q_wrap": 0, "u_wrap": 0, "v_clip": 0}
    wide_needed = False
    emu_outputs = []
    for start in range(0, n, CHUNK):
        x = x_all[start:start + CHUNK]
        p_a, s_a = _ir_run(lowered.trained, x, names)
        if lowered.order is lowered.trained:
            p_b, s_b = p_a, s_a
        else:
            p_b, s_b = _ir_run(lowered.order, x, names)
        if lowered.deployed is None:
            p_r = p_a
        else:
            p_r = p_b if lowered.order is lowered.deployed else _ir_run(lowered.deployed, x, names)[0]
        p_c, s_c = _ir_run(lowered.quantized, x, names)
        if mode == "batch":
            res = emulate(net, pad(x, lead), record="all")
        else:
            res = emulate(net, pad(x, lead), record="all", mode="stream", gap=int(options.get("gap", 100)))
        s_d = loihi_spikes(res, lowered.network, lowered.layers, lowered.timing_record.shifts, steps)
        p_d = np.argmax(s_d[names[-1]].sum(axis=1), axis=1)
        if plan is not None:
            from snncc.targets.loihi.mapping.relays import emulate_relayed

            kw = {"mode": "stream", "gap": int(options.get("gap", 100))} if mode != "batch" else {}
            s_e = loihi_spikes(emulate_relayed(relayed, plan, pad(x, lead), **kw), lowered.network, lowered.layers,
                               lowered.timing_record.shifts, steps)
            preds["relayed"].append(np.argmax(s_e[names[-1]].sum(axis=1), axis=1))
        for k, v in res.overflow.items():
            overflow[k] += v
        emu_outputs.append((x, mode))
        w = x.shape[0]
        for nm in names:
            agree_sum["emulator_vs_trained"][nm] += float(np.mean(s_d[nm] == s_a[nm])) * w
            agree_sum["emulator_vs_quantized_ir"][nm] += float(np.mean(s_d[nm] == s_c[nm])) * w
            agree_sum["loihi_order_vs_trained"][nm] += float(np.mean(s_b[nm] == s_a[nm])) * w
        for key, p in (("float_trained", p_a), ("ir_reset_changed", p_r), ("ir_loihi_order", p_b),
                       ("ir_quantized", p_c), ("emulator", p_d)):
            preds[key].append(np.asarray(p))
        if any(res.overflow.values()):
            wide_needed = True
        if progress is not None:
            progress(w)
    if wide_needed:
        for x, m in emu_outputs:
            kw = {"mode": "stream", "gap": int(options.get("gap", 100))} if m == "stream" else {}
            r = emulate(net, pad(x, lead), wide=True, **kw)
            counts = r.output_spikes[:, shift:shift + steps].sum(axis=1)
            preds["emulator_wide"].append(np.argmax(counts, axis=1))
    else:
        preds["emulator_wide"] = preds["emulator"]
    if plan is None:
        preds["relayed"] = preds["emulator"]
    p = {k: np.concatenate(v) for k, v in preds.items()}
    acc = {k: float(np.mean(v == labels)) for k, v in p.items()}
    loss = {
        "reset": 100 * (acc["float_trained"] - acc["ir_reset_changed"]),
        "timing": 100 * (acc["ir_reset_changed"] - acc["ir_loihi_order"]),
        "quantization": 100 * (acc["ir_loihi_order"] - acc["ir_quantized"]),
        "integer_truncation": 100 * (acc["ir_quantized"] - acc["emulator_wide"]),
        "overflow": 100 * (acc["emulator_wide"] - acc["emulator"]),
        "total": 100 * (acc["float_trained"] - acc["emulator"]),
    }
    if plan is not None:
        loss["relays"] = 100 * (acc["emulator"] - acc["relayed"])
        loss["total"] = 100 * (acc["float_trained"] - acc["relayed"])
    notes = []
    if lowered.timing_record.changes:
        notes += [f"timing: {c}" for c in lowered.timing_record.changes]
    if plan is not None:
        notes += plan.notes()
    if options.get("synthetic"):
        notes.append("the data set is synthetic: these accuracies are not the paper's")
    return CheckRecord(
        target="loihi", samples=n, steps=steps, timing=lowered.timing_record.mode,
        scale_rule=lowered.quant_record.rule, scale_reason=lowered.quant_record.reason,
        accuracy={k: acc[k] for k in ("float_trained", "ir_reset_changed", "ir_loihi_order", "ir_quantized", "emulator")
                  + (("relayed",) if plan is not None else ())},
        loss_points=loss,
        spike_agreement={k: {nm: v / n for nm, v in d.items()} for k, d in agree_sum.items()},
        prediction_agreement={
            "emulator_vs_trained": float(np.mean(p["emulator"] == p["float_trained"])),
            "emulator_vs_quantized_ir": float(np.mean(p["emulator"] == p["ir_quantized"])),
            "loihi_order_vs_trained": float(np.mean(p["ir_loihi_order"] == p["float_trained"])),
            **({"relayed_vs_emulator": float(np.mean(p["relayed"] == p["emulator"]))} if plan is not None else {}),
        },
        overflow=overflow, mode=mode, notes=notes, reset_changed=lowered.deployed is not None,
    )
