"""SynSense Xylo's number formats and limits, stated once, as plain data (docs/xylo.md).

``CORE`` is the arithmetic of the Xylo v2 SNN core as the vendor's bit-exact simulator models it
(``xylosim`` 0.1.3, ``src/v2/cpp``): all three chips below run it (Rockpool simulates Xylo Audio 2
with ``syns61201.XyloSim`` and Xylo IMU and Xylo Audio 3 with ``syns63300.XyloSim``; both build the
same ``xylosim.v2.XyloLayer``). ``CHIPS`` holds the per-chip sizes, keyed by part number in lower
case ("syns61201", the default, "syns63300", "syns65302"). Every Xylo module reads its limits from
here; nothing here imports anything of snncc.

Each value says where it comes from (``sources`` at the foot): ``C++`` is xylosim's source,
``rockpool`` Rockpool 3.1.0's mapper / ``config_from_specification``, ``overview`` Rockpool's
published "Overview of the Xylo family" table. A value marked ASSUMED is in none of them.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class CoreArithmetic:
    """Widths, ranges and caps of the v2 core's integer arithmetic (identical on all three chips)."""

    simulator: str = "xylosim.v2"
    state_bits: int = 16          # Isyn, Isyn2, Vmem: int16, saturating (XyloIAFNeuron.h:1, 22-28)
    weight_bits: int = 8          # weights: int8 (XyloLayer.h:15)
    weight_shift_min: int = 0     # left shift of every weight of one matrix (XyloLayer.cpp:383)
    weight_shift_max: int = 15    # ASSUMED 4-bit register; xylosim takes any int8, samna's range is unpublished
    dash_bits: int = 4            # bit-shift decays: 0 .. 15 ("should be 4 bits", XyloIAFNeuron.h:20-21)
    threshold_bits: int = 16      # int16 (XyloIAFNeuron.h:22); rockpool quantises to 16 signed bits
    bias_bits: int = 16           # int16 in xylosim (XyloIAFNeuron.h:24); the silicon width is unpublished
    max_input_spikes: int = 15    # input events per channel and step (MAX_NUM_INP_SPIKES, XyloIAFNeuron.h:3)
    max_hidden_spikes: int = 31   # events a hidden neuron emits per step (MAX_NUM_SPIKES, XyloIAFNeuron.h:4)
    max_output_spikes: int = 1    # events an output neuron emits per step (MAX_NUM_OUT_SPIKES, XyloIAFNeuron.h:5)
    hidden_synapse_states: int = 2  # Isyn and Isyn2 per hidden neuron, as rockpool's from_specification builds them
    output_synapse_states: int = 1  # one synaptic current per output neuron

    @property
    def state_min(self) -> int:
        return -(1 << (self.state_bits - 1))

    @property
    def state_max(self) -> int:
        return (1 << (self.state_bits - 1)) - 1

    @property
    def weight_min(self) -> int:
        return -(1 << (self.weight_bits - 1))

    @property
    def weight_max(self) -> int:
        return (1 << (self.weight_bits - 1)) - 1

    @property
    def dash_max(self) -> int:
        return (1 << self.dash_bits) - 1

    @property
    def threshold_min(self) -> int:
        return -(1 << (self.threshold_bits - 1))

    @property
    def threshold_max(self) -> int:
        return (1 << (self.threshold_bits - 1)) - 1

    @property
    def bias_min(self) -> int:
        return -(1 << (self.bias_bits - 1))

    @property
    def bias_max(self) -> int:
        return (1 << (self.bias_bits - 1)) - 1


CORE = CoreArithmetic()


@dataclass(frozen=True)
class XyloChip:
    """One Xylo chip: its sizes and connection limits; its arithmetic is ``core``."""

    key: str                      # "syns61201" ...: how snncc names the chip (--chip)
    name: str
    part_number: str
    max_inputs: int               # input channels
    max_hidden: int               # hidden neurons
    max_outputs: int              # output (readout) neurons
    synapses_per_hidden: int      # synaptic currents a hidden neuron can be given input on (1: Isyn only)
    max_input_expansion: int      # hidden neurons input weights may reach: the first ones (IENs)
    max_output_expansion: int     # hidden neurons output weights may come from: the last ones (OENs)
    max_fanout: int               # recurrent targets of one hidden neuron
    max_alias_targets: int        # alias targets of one hidden neuron
    sources: tuple[tuple[str, str], ...] = ()   # (field, where the value comes from)
    core: CoreArithmetic = CORE

    def source(self, field: str) -> str:
        return dict(self.sources).get(field, "")


_COMMON_SOURCES = (
    ("max_inputs", "rockpool le_16_input_channels; overview"),
    ("max_alias_targets", "rockpool config_from_specification keeps aliases[i][0] only; overview: 1 alias per neuron"),
    ("max_fanout", "overview 'Max. fanout' (not checked by rockpool 3.1.0 or xylosim)"),
)

AUDIO2 = XyloChip(
    key="syns61201", name="Xylo Audio 2", part_number="SYNS61201",
    max_inputs=16, max_hidden=1000, max_outputs=8, synapses_per_hidden=2,
    max_input_expansion=1000, max_output_expansion=1000, max_fanout=64, max_alias_targets=1,
    sources=_COMMON_SOURCES + (
        ("max_hidden", "rockpool syns61201 mapper max_hidden_neurons=1000; overview"),
        ("max_outputs", "rockpool syns61201 mapper max_output_neurons=8; overview"),
        ("synapses_per_hidden", "overview 'Num. Syn. states' 2; samna synapse2_enable"),
        ("max_input_expansion", "overview: input projection to 1000 hidden neurons"),
        ("max_output_expansion", "overview: output projection from 1000 hidden neurons; the board's weights_out has "
                                 "one row per hidden neuron"),
    ),
)

IMU = XyloChip(
    key="syns63300", name="Xylo IMU", part_number="SYNS63300",
    max_inputs=16, max_hidden=496, max_outputs=16, synapses_per_hidden=1,
    max_input_expansion=128, max_output_expansion=128, max_fanout=512, max_alias_targets=1,
    sources=_COMMON_SOURCES + (
        ("max_hidden", "rockpool syns63300 mapper max_hidden_neurons=496; overview"),
        ("max_outputs", "rockpool syns63300 mapper max_output_neurons=16; overview"),
        ("synapses_per_hidden", "rockpool syns63300 DRC max_synapses_per_neuron=1, config_from_specification refuses "
                                "Nsyn > 1; overview"),
        ("max_input_expansion", "rockpool syns63300 config_from_specification keeps the first 128 IENs; overview"),
        ("max_output_expansion", "rockpool syns63300 config_from_specification keeps the last 128 OENs; overview"),
    ),
)

AUDIO3 = XyloChip(
    key="syns65302", name="Xylo Audio 3", part_number="SYNS65302",
    max_inputs=16, max_hidden=992, max_outputs=32, synapses_per_hidden=2,
    max_input_expansion=128, max_output_expansion=128, max_fanout=1024, max_alias_targets=1,
    sources=_COMMON_SOURCES + (
        ("max_hidden", "rockpool syns65302 mapper max_hidden_neurons=992; overview"),
        ("max_outputs", "rockpool syns65302 mapper max_output_neurons=32; overview (its DRC only warns above 16)"),
        ("synapses_per_hidden", "overview 'Num. Syn. states' 2; samna synapse2_enable"),
        ("max_input_expansion", "rockpool syns65302 config_from_specification keeps the first 128 IENs; overview"),
        ("max_output_expansion", "rockpool syns65302 config_from_specification keeps the last 128 OENs; overview"),
    ),
)

CHIPS: dict[str, XyloChip] = {c.key: c for c in (AUDIO2, IMU, AUDIO3)}
DEFAULT_CHIP = AUDIO2.key


def get_chip(key: str | XyloChip | None = None) -> XyloChip:
    """The chip record for ``key`` (a key of ``CHIPS``, case-insensitive; None: the default).

    An unknown key raises ``KeyError`` naming the known ones (callers turn it into their error)."""
    if isinstance(key, XyloChip):
        return key
    name = DEFAULT_CHIP if key is None else str(key).lower()
    if name not in CHIPS:
        raise KeyError(f"unknown Xylo chip {key!r} (known: {', '.join(CHIPS)})")
    return CHIPS[name]
