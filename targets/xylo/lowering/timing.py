"""Xylo's time model in the IR's terms, and the shifts that make a lowered model exact in time.

Xylo (xylosim v2, one step): input events of step t reach hidden neurons in step t (delay 0);
hidden spikes of step t reach hidden neurons and output neurons in step t + 1 (delay 1). No other
delay exists (no synaptic delay, no refractory period).

A population P runs ``s_P`` steps late on the chip: its chip spikes at t + s_P are the IR's at t
(the input too: the chip's input stream is the IR's delayed by ``s_input``). A projection
pre -> post with IR delay d and chip delay c is exact iff ``c = d + s_post - s_pre``; these are
equalities (the chip has no programmable delay), so a loop is exact only if its IR delays equal
its chip delays (a self-recurrent loop: IR delay 1). The solution is normalised to min s = 0:
the chip runs the sample with ``input_pad`` = s_input zero steps before it and reads output
spikes from chip step ``output_lag`` = s_output on, so counts over the sample are unchanged.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from snncc.targets.kit import SnnccError
from snncc.ir.graph import Graph
from snncc.targets.xylo.lowering.structure import Population

CHIP_DELAY_INPUT = 0      # input -> hidden
CHIP_DELAY_HIDDEN = 1     # hidden -> hidden, hidden -> output


@dataclass
class XyloTiming:
    shifts: dict[str, int]                   # population (and the Input) -> steps late on the chip
    input_pad: int                           # zero steps fed before the sample
    output_lag: int                          # chip steps before the readout's first IR step
    ir_delays: dict[str, int] = field(default_factory=dict)   # projection -> IR delay
    chip_delays: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def projection_delay(graph: Graph, pre: str, dense: str, post: str) -> int:
    return graph.delay(pre, dense) + graph.delay(dense, post)


def solve_timing(graph: Graph, pops: list[Population], readout_extra: int = 0) -> XyloTiming:
    """Shifts for a chain of populations; ``readout_extra`` adds chip steps behind the last population
    (1 when it runs on hidden proxies relayed to the output neurons)."""
    shift: dict[str, int] = {pops[0].pre: 0}
    ir_d: dict[str, int] = {}
    chip_d: dict[str, int] = {}
    for k, p in enumerate(pops):
        d = projection_delay(graph, p.pre, p.ff, p.lif)
        c = CHIP_DELAY_INPUT if k == 0 else CHIP_DELAY_HIDDEN
        shift[p.lif] = shift[p.pre] + c - d
        key = f"{p.pre}->{p.lif}"
        ir_d[key], chip_d[key] = d, c
        if p.rec is not None:
            dr = projection_delay(graph, p.lif, p.rec, p.lif)
            ir_d[f"{p.lif}->{p.lif}"], chip_d[f"{p.lif}->{p.lif}"] = dr, CHIP_DELAY_HIDDEN
            if dr != CHIP_DELAY_HIDDEN:
                raise SnnccError(f"a recurrent projection with IR delay {dr} steps; Xylo's recurrent spikes arrive "
                                 f"exactly {CHIP_DELAY_HIDDEN} step later (no other delay exists)",
                                 field=f"edge {p.lif}->{p.rec}->{p.lif}")
    low = min(shift.values())
    shift = {k: v - low for k, v in shift.items()}
    last = pops[-1].lif
    timing = XyloTiming(shifts=shift, input_pad=shift[pops[0].pre], output_lag=shift[last] + readout_extra,
                        ir_delays=ir_d, chip_delays=chip_d)
    moved = {k: v for k, v in shift.items() if v}
    if moved or readout_extra:
        timing.notes.append(
            f"chip delays differ from the IR's ({', '.join(f'{k}: IR {ir_d[k]}, chip {chip_d[k]}' for k in ir_d)}): "
            f"populations run late by {moved or 0} steps{' (+1 for the output relay)' if readout_extra else ''}; "
            f"the chip is fed {timing.input_pad} zero step(s) before a sample and its output is read from step "
            f"{timing.output_lag} on, so spike trains and counts equal the IR's")
    return timing
