"""The Loihi artefact: the lowered network with its quantization, timing and validation records.

``write(path)`` writes the HDF5 bundle (a fine-tuned one with its ``finetune`` record); ``summary()`` is the record as plain data (what
``snncc compile --json`` prints); ``render_text(console)`` prints it for people (``report_text.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snncc.targets.loihi.bundle.write import netx_compat, write_bundle
from snncc.targets.loihi.network import LoihiNetwork
from snncc.targets.loihi.lowering.report_text import delay_text, exp_text, register_text


@dataclass
class LoihiArtefact:
    network: LoihiNetwork
    quantization: dict[str, Any]
    timing: dict[str, Any]
    validation: dict[str, Any]
    notes: list[str] = field(default_factory=list)
    liveness: dict[str, Any] = field(default_factory=dict)      # populations' activity on the calibration inputs
    portability: dict[str, Any] = field(default_factory=dict)   # netx runs it as written? (bundle/portability.py)
    finetune: dict[str, Any] | None = None   # a fine-tuned bundle's record (kit.finetuned.finetune_entry)
    model: dict[str, Any] | None = None      # kit.artefact.model_record of the graph as given (/snncc/model)

    def write(self, path: str | Path) -> None:
        extra = {"quantization": self.quantization, "timing": self.timing, "validation": self.validation}
        if self.liveness:
            extra["liveness"] = self.liveness
        if self.portability:
            extra["portability"] = self.portability
        if self.finetune is not None:
            extra["finetune"] = self.finetune
        if self.model is not None:
            extra["model"] = self.model
        write_bundle(self.network, path, extra=extra)

    def float_calibration_activity(self, steps: int) -> dict[str, Any] | None:
        """``targets.base.KnowsFloatActivity``: the liveness record's float figures (the model as given, or its
        exact replica, whose population names then differ) on the calibration inputs, where they ran ``steps``."""
        from snncc.ir.liveness import SpikeActivity, calibration_text

        if self.liveness.get("inputs") != calibration_text(steps) or "float" not in self.liveness:
            return None
        fields = set(SpikeActivity.__dataclass_fields__)
        return {name: SpikeActivity(**{k: v for k, v in figures.items() if k in fields})
                for name, figures in self.liveness["float"].items()}

    def summary(self) -> dict[str, Any]:
        net = self.network
        q = self.quantization
        return {
            "format": "HDF5 bundle, lava-dl netx layout (+ snncc groups at /snncc)",
            "t_sample": net.t_sample,
            "layers": [
                {"index": i, "name": lay.name, "type": lay.kind, "neurons": lay.n, "bias_sources": lay.always_on,
                 **({} if i == 0 else {"vThMant": register_text(lay.v_th_mant), "iDecay": register_text(lay.i_decay),
                                       "vDecay": register_text(lay.v_decay),
                                       "refDelay": lay.ref_delay, "wgtExp": exp_text(lay.wgt_exp),
                                       **({"wgtExpRec": exp_text(lay.wgt_exp_rec)} if lay.weight_rec is not None
                                          else {}),
                                       "delay": delay_text(lay.delay),
                                       **({"delay_rec": delay_text(lay.delay_rec)} if lay.weight_rec is not None else {})})}
                for i, lay in enumerate(net.layers)
            ],
            "scale_rule": q["rule"], "scale_reason": q["reason"], "w_scale": q["w_scale"],
            "scale_candidates": (q.get("calibration") or {}).get("errors", {}),
            "weights_clipped": q["clipped_total"],
            "timing": self.timing["mode"], "timing_changes": self.timing["changes"],
            "validation": self.validation,
            "netx_compat": netx_compat(net),
            "portability": self.portability,
            "liveness": self.liveness,
            "core_map": net.core_map,
            "notes": self.notes,
        }

    def render_text(self, console) -> None:
        from snncc.targets.loihi.lowering.report_text import render_compile_report

        render_compile_report(self.summary(), console)
