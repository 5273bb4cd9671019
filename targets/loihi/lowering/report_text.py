"""The compile report as text: what ``snncc compile --target loihi`` prints from ``LoihiArtefact.summary()``.

Register values read as text: one value -> the integer; per-neuron values -> "per-neuron lo..hi
(k values)"; per-synapse delays -> "per-synapse lo..hi"; per-synapse weight exponents ->
"per-synapse e (count), ...".
"""

from __future__ import annotations

from typing import Any

import numpy as np

from snncc.targets.loihi.bundle.portability import PER_NEURON_NOTE
from snncc.targets.loihi.mapping.coremap import CoreMap


def render_compile_report(s: dict[str, Any], console) -> None:
    """Print ``LoihiArtefact.summary()`` ``s`` for people."""
    console.print(f"[bold]Loihi bundle[/bold]: tSample {s['t_sample']}, timing '{s['timing']}', "
                  f"scale rule '{s['scale_rule']}'" + (f", w_scale {s['w_scale']}" if s["w_scale"] else ""))
    console.print(f"  scale: {s['scale_reason']}")
    if s["scale_candidates"]:
        console.print("  scale candidates, measured spike-count error on the calibration inputs (lower is better): "
                      + ", ".join(f"{k} {'undefined (outputs silent in float)' if v is None else f'{v:.4f}'}"
                                  for k, v in s["scale_candidates"].items()))
    for lay in s["layers"]:
        sources = lay["bias_sources"]
        if lay["index"] == 0:
            console.print(f"  layer 0  input      {lay['neurons'] - sources} axons"
                          + (f" + {sources} always-on (current biases)" if sources else ""))
            continue
        rec = f" wgtExpRec {lay['wgtExpRec']} delay_rec {lay['delay_rec']}" if "wgtExpRec" in lay else ""
        extra = f" + {sources} bias sources" if sources else ""
        console.print(f"  layer {lay['index']}  {lay['type']:<9}  {lay['neurons'] - sources} neurons{extra}  "
                      f"vThMant {lay['vThMant']} "
                      f"iDecay {lay['iDecay']} vDecay {lay['vDecay']} refDelay {lay['refDelay']} "
                      f"wgtExp {lay['wgtExp']} delay {lay['delay']}{rec}")
    if s["weights_clipped"]:
        console.print(f"  [yellow]{s['weights_clipped']} weight(s) rounded beyond the 8-bit range and were clipped "
                      "(e.g. +256 -> 254)[/yellow]")
    for change in s["timing_changes"]:
        console.print(f"  [yellow]timing: {change}[/yellow]")
    v = s["validation"]
    exact = v["timing_exact"] and v["quantized_params_exact"] and v["kernel_exact"]
    console.print(f"  checked on {v['inputs']}: " + ("exact" if exact else "NOT exact") + f" (timing {v['timing_exact']}, "
                  f"quantized registers {v['quantized_params_exact']}, emulator kernel {v['kernel_exact']})",
                  markup=False)
    counts = v.get("spike_counts") or {}
    if counts:
        console.print("  spikes on them, emulated vs float model as trained: "
                      + ", ".join(f"{k} {counts['emulator'][k]:,} vs {counts['float'][k]:,}" for k in counts["emulator"])
                      + "; for the bundle's agreement with the float model: `snncc check MODEL --artefact BUNDLE` "
                      "(1,000 samples by default)", markup=False)
    if any(v["overflow"].values()):
        console.print(f"  [yellow]overflow on the check inputs: {v['overflow']}[/yellow]")
    live = s.get("liveness") or {}
    for line in live.get("flagged", []):
        console.print(f"  liveness on the calibration inputs: {line}", markup=False, style="yellow")
    port = s.get("portability") or {}
    if port:
        console.print(f"  {port['line']}", markup=False, style=None if port["netx_runnable"] else "yellow")
        best = port.get("best_netx_rule")
        if not port["netx_runnable"] and best:
            chosen = port.get("chosen_error")
            console.print(f"  best bundle under a rule netx can run (the model's own needs aside): '{best['rule']}', "
                          f"calibration spike-count error {best['error']:.4f}"
                          + (f" (this bundle: {chosen:.4f})" if chosen is not None else ""), markup=False)
    for note in s["netx_compat"]:
        console.print(f"  [yellow]netx compatibility: {note}[/yellow]")
    if any(PER_NEURON_NOTE not in note for note in s["netx_compat"]):
        console.print("  [yellow]lava-dl netx ignores the fields above, so Lava would run this bundle differently "
                      "than the chip semantics snncc emulates.[/yellow]")
    if s["core_map"] is not None:
        console.print(f"  core map: {CoreMap.from_dict(s['core_map']).n_cores} cores")
    for note in s["notes"]:
        console.print(f"  note: {note}")


def delay_text(delay) -> Any:
    d = np.asarray(delay)
    return int(d) if d.ndim == 0 else f"per-synapse {int(d.min())}..{int(d.max())}"


def register_text(value) -> Any:
    v = np.asarray(value)
    return int(v) if v.ndim == 0 else f"per-neuron {int(v.min())}..{int(v.max())} ({len(np.unique(v))} values)"


def exp_text(exp) -> Any:
    e = np.asarray(exp)
    if e.ndim == 0:
        return int(e)
    values, counts = np.unique(e, return_counts=True)
    return "per-synapse " + ", ".join(f"{int(v)} ({int(c)})" for v, c in zip(values, counts))
