"""What a written artefact costs on its hardware, in one record every target fills the same way (the capability
``profile``; ``snncc compare`` lays the records of several targets side by side).

    resources     each a ``Resource``: what is counted (cores, neurons, synapses, flash, RAM, ...), how much the
                  artefact uses and the chip's limit (None where the chip states none)
    real_time     ``RealTime``: whether a time step is computed within dt at the event rates measured on the
                  inputs given (the expected load), the margin (dt / time per step) and the worst case beside it,
                  and what the figures rest on (an ESTIMATE from a stated cost model, or a measurement)
    energy        ``EnergyEstimate``: energy (and delay) per sample where a published cost model exists, always an
                  ESTIMATE with its source; None where none exists (never invented)
    neurobench    NeuroBench 2.3's metrics of the artefact (``kit.neurobench``: its synapses as stored, the spikes of
                  its own emulation or run on the inputs given)
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from snncc.measure.neurobench import NeuroBenchFigures


@dataclass
class Resource:
    what: str
    used: float
    limit: float | None = None
    unit: str = ""

    def text(self) -> str:
        used = f"{self.used:,.0f}" if float(self.used).is_integer() else f"{self.used:,.3g}"
        limit = "" if self.limit is None else f" / {self.limit:,.0f}"
        return f"{self.what} {used}{limit}{' ' + self.unit if self.unit else ''}"


@dataclass
class RealTime:
    real_time: bool
    margin: float                  # dt / time per step at the measured event rates (> 1: real time)
    worst_margin: float | None     # the same at the worst case the cost model allows
    basis: str                     # "ESTIMATE: ..." or "measured: ..."

    def text(self) -> str:
        worst = "" if self.worst_margin is None else f" (worst case {self.worst_margin:.2f}x)"
        return f"{'yes' if self.real_time else 'NO'}, margin {self.margin:.2f}x at the measured event rates{worst}"


@dataclass
class EnergyEstimate:
    uj_per_sample: float
    delay_ms_per_sample: float | None
    source: str
    label: str = "ESTIMATE"

    def text(self) -> str:
        delay = "" if self.delay_ms_per_sample is None else f", {self.delay_ms_per_sample:.3g} ms"
        return f"{self.uj_per_sample:.3g} uJ{delay} per sample ({self.label}: {self.source})"


@dataclass
class Profile:
    """The ``profile`` capability's record (module doc)."""

    target: str
    resources: list[Resource]
    neurobench: NeuroBenchFigures | None          # None: a model NeuroBench's spiking metrics do not cover (an LSTM)
    real_time: RealTime | None = None
    energy: EnergyEstimate | None = None
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def lines(self) -> list[str]:
        out = ["resources: " + ", ".join(r.text() for r in self.resources)]
        if self.real_time is not None:
            out.append(f"real time: {self.real_time.text()} ({self.real_time.basis})")
        out.append("energy: " + ("no published cost model for this target" if self.energy is None else self.energy.text()))
        nb = self.neurobench
        if nb is not None:
            ops = nb.synaptic_operations
            out.append(f"NeuroBench: footprint {nb.footprint:,} B, connection sparsity {nb.connection_sparsity:.3f}, "
                       f"activation sparsity {nb.activation_sparsity:.4f}, synaptic operations per sample "
                       f"{ops['Effective_ACs']:,.0f} ACs + {ops['Effective_MACs']:,.0f} MACs (dense {ops['Dense']:,.0f})")
        return out + [f"note: {n}" for n in self.notes]

    def render_text(self, console: Any) -> None:
        for line in self.lines():
            console.print(line, markup=False, highlight=False, soft_wrap=True)


__all__ = ["Profile", "Resource", "RealTime", "EnergyEstimate", "NeuroBenchFigures"]
