"""Per-chip limits of the Xylo family, as plain data (the figures the design rules and the lowering use).

A local table until ``targets/xylo/chip.py`` (xylo-core) lands; the names this package reads are
the fields of ``XyloChip``. Sources: xylosim 0.1.3's C++ (``src/v2/cpp/XyloIAFNeuron.h``: 16-bit
states, 8-bit weights, 31 spikes per hidden neuron and step, 1 per output neuron, 15 input events
per channel and step) and Rockpool 3.1's mappers and design-rule checks (neuron counts,
expansion-neuron limits).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class XyloChip:
    key: str                     # --chip value
    name: str
    part: str
    inputs: int                  # input channels
    hidden: int                  # hidden (reservoir) neurons
    outputs: int                 # output (readout) neurons
    synapses: int                # synaptic currents per hidden neuron
    input_expansion: int | None  # hidden neurons that may receive input weights (None: all)
    output_expansion: int | None # hidden neurons that may send output weights (None: all)
    max_spikes_hidden: int = 31  # spikes a hidden neuron may emit in one step
    max_spikes_output: int = 1
    max_input_events: int = 15   # input events per channel and step
    weight_bits: int = 8
    state_bits: int = 16
    dash_max: int = 15           # 4-bit bit-shift decays
    weight_shift_max: int = 15   # 4-bit register; shifts above 8 wrap every weight but 0 and -1 in int16


AUDIO2 = XyloChip("audio2", "Xylo Audio 2", "SYNS61201", inputs=16, hidden=1000, outputs=8, synapses=2,
                  input_expansion=None, output_expansion=None)
IMU = XyloChip("imu", "Xylo IMU", "SYNS63300", inputs=16, hidden=496, outputs=16, synapses=1,
               input_expansion=128, output_expansion=128)
AUDIO3 = XyloChip("audio3", "Xylo Audio 3", "SYNS65302", inputs=16, hidden=992, outputs=32, synapses=2,
                  input_expansion=128, output_expansion=128)
CHIPS: dict[str, XyloChip] = {c.key: c for c in (AUDIO2, IMU, AUDIO3)}

STATE_MAX = 2 ** 15 - 1      # int16
STATE_MIN = -(2 ** 15)
WEIGHT_MAX = 127
WEIGHT_MIN = -128
SAFE_WEIGHT_SHIFT = 8        # the largest shift under which no int8 weight wraps in int16
