"""Resource model of a neuromorphic chip as plain data, and the design rules a core must obey.

Loihi 1 (Davies et al., IEEE Micro 2018; nengo-loihi 1.x ``block.py`` / hardware builder):

    per chip   128 neuro cores (4 per tile; tiles assumed on an 8 east-west x 4 north-south mesh)
    per core   1,024 compartments, 4,096 input axons, 4,096 output axons,
               16,384 x 64-bit words of synapse memory (1,048,576 bits),
               8 threshold (vth) profiles and 32 compartment profiles,
               synaptic delays up to 62 steps.

The profile limits are the ones nengo-loihi's *hardware* builder asserts (8 vth / 32 cx profiles);
its emulator-side validator allows 16 vth profiles, but the hardware builder's numbers are what a
core can actually be programmed with, so the stricter pair is used.

Synapse memory (nengo-loihi's accounting): the weights of one input axon into one core are stored
per projection as a list cut into chunks of at most 64 synapses; a chunk of ``n`` synapses costs
``n * b + 4 + 6`` bits (4-bit synapse-format id, 6-bit synapse count) rounded up to whole 64-bit
words, where ``b`` = 8 weight bits + delay bits (+ index bits in the sparse format). So one axon to
64 neurons costs 576 bits and a dense 1000 -> 1000 layer 1000 * 9,024 = 9,024,000 bits.

Another chip is described by another ``ChipSpec`` (and ``EnergyCosts``) with the same fields.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from snncc.targets.loihi import chip


@dataclass(frozen=True)
class EnergyCosts:
    """Energy (pJ) and time (ns) per operation: Davies 2018 Table 2 (pre-silicon, 0.75 V)."""

    synop_pj: float = 23.6
    synop_ns: float = 3.5
    update_active_pj: float = 81.0
    update_active_ns: float = 8.4
    update_inactive_pj: float = 52.0
    update_inactive_ns: float = 5.3
    spike_in_tile_pj: float = 1.7
    spike_in_tile_ns: float = 2.1
    hop_ew_pj: float = 3.0
    hop_ew_ns: float = 4.1
    hop_ns_pj: float = 4.0
    hop_ns_ns: float = 6.5
    barrier_min_ns: float = 113.0      # barrier synchronisation across 1 tile ...
    barrier_max_ns: float = 465.0      # ... and across 32 tiles (linear in between; see estimate/energy.py)
    barrier_max_tiles: int = 32
    source: str = "Davies et al., IEEE Micro 2018, Table 2 (pre-silicon, 0.75 V)"


@dataclass(frozen=True)
class ChipSpec:
    """Per-chip and per-core limits of a neuromorphic chip, plus its synapse-memory encoding.

    The defaults are Loihi 1's (``chip.py``), read when an instance is built."""

    name: str = "Loihi 1"
    cores_per_chip: int = field(default_factory=lambda: chip.CORES_PER_CHIP)
    compartments_per_core: int = field(default_factory=lambda: chip.COMPARTMENTS_PER_CORE)
    input_axons_per_core: int = field(default_factory=lambda: chip.INPUT_AXONS_PER_CORE)
    output_axons_per_core: int = field(default_factory=lambda: chip.OUTPUT_AXONS_PER_CORE)
    synapse_words_per_core: int = field(default_factory=lambda: chip.SYNAPSE_WORDS_PER_CORE)
    word_bits: int = field(default_factory=lambda: chip.SYNAPSE_WORD_BITS)
    weight_bits: int = field(default_factory=lambda: chip.WEIGHT_BITS)
    synapses_per_chunk: int = field(default_factory=lambda: chip.SYNAPSES_PER_CHUNK)
    chunk_header_bits: int = field(default_factory=lambda: chip.CHUNK_HEADER_BITS)
    min_index_bits: int = field(default_factory=lambda: chip.INDEX_BITS_MIN)
    max_index_bits: int = field(default_factory=lambda: chip.INDEX_BITS_MAX)
    vth_profiles_per_core: int = field(default_factory=lambda: chip.VTH_PROFILES_PER_CORE)
    compartment_profiles_per_core: int = field(default_factory=lambda: chip.COMPARTMENT_PROFILES_PER_CORE)
    voltage_limits_per_core: int = field(default_factory=lambda: chip.VOLTAGE_LIMITS_PER_CORE)
    max_delay: int = field(default_factory=lambda: chip.MAX_EXTRA_DELAY)
    cores_per_tile: int = field(default_factory=lambda: chip.CORES_PER_TILE)
    mesh_tiles_ew: int = field(default_factory=lambda: chip.MESH_TILES_EW)
    mesh_tiles_ns: int = field(default_factory=lambda: chip.MESH_TILES_NS)
    max_chips: int | None = None            # None: as many chips as needed (multi-chip boards)
    energy: EnergyCosts = field(default_factory=EnergyCosts)

    @property
    def synapse_bits_per_core(self) -> int:
        return self.synapse_words_per_core * self.word_bits

    def limits(self) -> dict[str, int]:
        """Per-core limits by resource name (the names used in core maps and error messages)."""
        return {
            "neurons": self.compartments_per_core,
            "input_axons": self.input_axons_per_core,
            "output_axons": self.output_axons_per_core,
            "synapse_bits": self.synapse_bits_per_core,
            "vth_profiles": self.vth_profiles_per_core,
            "compartment_profiles": self.compartment_profiles_per_core,
            "voltage_limits": self.voltage_limits_per_core,
        }

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "ChipSpec":
        d = dict(d)
        energy = EnergyCosts(**d.pop("energy", {}))
        return cls(**d, energy=energy)


LOIHI1 = ChipSpec()    # Loihi 1 as chip.py states it when this module is imported

LIMIT_TITLES = {
    "neurons": "compartments per core",
    "input_axons": "input axons (fan-in) per core",
    "output_axons": "output axons (fan-out) per core",
    "synapse_bits": "synapse memory bits per core",
    "vth_profiles": "threshold (vth) profiles per core",
    "compartment_profiles": "compartment profiles per core",
    "voltage_limits": "voltage-limit settings (vmin/vmax) per core",
    "delay": "synaptic delay (steps)",
    "cores": "cores in the system",
}


# -- synapse memory -----------------------------------------------------------------------------
def delay_bits(max_delay: int) -> int:
    """Bits per synapse for a delay field holding 0..max_delay (0 bits when every delay is 0)."""
    return 0 if max_delay <= 0 else int(math.ceil(math.log2(max_delay + 1)))


def index_bits(n_compartments, chip: ChipSpec = LOIHI1) -> np.ndarray:
    """Sparse format: bits to index a compartment within a range of n, clamped to the chip's 6..12."""
    n = np.maximum(np.asarray(n_compartments, np.int64), 1)
    need = np.ceil(np.log2(n)).astype(np.int64)
    return np.clip(need, chip.min_index_bits, chip.max_index_bits)


def list_bits(n_synapses, bits_per_synapse, chip: ChipSpec = LOIHI1) -> np.ndarray:
    """Bits used by synapse lists of n synapses each: chunks of <= 64, each n*b + 10 rounded to 64.

    Vectorised over ``n_synapses`` (and ``bits_per_synapse``); a list of 0 synapses costs 0.
    """
    n = np.asarray(n_synapses, np.int64)
    b = np.asarray(bits_per_synapse, np.int64)
    per, word, head = chip.synapses_per_chunk, chip.word_bits, chip.chunk_header_bits
    full, rest = np.divmod(n, per)
    full_cost = -(-(per * b + head) // word) * word
    rest_cost = np.where(rest > 0, -(-(rest * b + head) // word) * word, 0)
    return full * full_cost + rest_cost


def axon_list_bits(n_nonzero, n_range, bits_per_weight, chip: ChipSpec = LOIHI1) -> np.ndarray:
    """Cheaper of the two encodings of one axon's synapses into a range of n_range compartments.

    dense format: every compartment of the range gets a weight slot (zeros included);
    sparse format: only the n_nonzero synapses, each with an index field.
    A list with no nonzero weight needs no synapse (and no input axon).
    """
    nnz = np.asarray(n_nonzero, np.int64)
    rng = np.asarray(n_range, np.int64)
    dense = list_bits(rng, bits_per_weight, chip)
    sparse = list_bits(nnz, np.asarray(bits_per_weight, np.int64) + index_bits(rng, chip), chip)
    return np.where(nnz == 0, 0, np.where(nnz >= rng, dense, np.minimum(dense, sparse)))


def min_bits_per_synapse(bits_per_weight: int, chip: ChipSpec = LOIHI1) -> float:
    """The fewest bits any synapse can cost under this encoding (best chunk fill), for lower bounds."""
    n = np.arange(1, chip.synapses_per_chunk + 1)
    return float(np.min(list_bits(n, bits_per_weight, chip) / n))


# -- design rules ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Violation:
    """One broken limit: which limit, on which core (None: not core-specific), caused by which layer."""

    limit: str
    value: int
    allowed: int
    core: int | None = None
    layer: str | None = None
    detail: str = ""

    def message(self) -> str:
        where = f"core {self.core}: " if self.core is not None else ""
        who = f"layer '{self.layer}': " if self.layer else ""
        extra = f" ({self.detail})" if self.detail else ""
        return (f"{where}{who}{LIMIT_TITLES.get(self.limit, self.limit)}: needs {self.value:,}, "
                f"limit {self.allowed:,}{extra}")


def _core_rule(resource: str):
    def rule(core: dict, chip: ChipSpec) -> list[Violation]:
        value, allowed = int(core[resource]), chip.limits()[resource]
        if value <= allowed:
            return []
        layers = ", ".join(s["layer"] for s in core.get("layers", [])) or None
        return [Violation(resource, value, allowed, core=core.get("core"), layer=layers)]

    rule.__name__ = f"check_{resource}"
    rule.__doc__ = f"A core's {LIMIT_TITLES[resource]} must not exceed the chip's limit."
    return rule


check_compartments = _core_rule("neurons")
check_input_axons = _core_rule("input_axons")
check_output_axons = _core_rule("output_axons")
check_synapse_bits = _core_rule("synapse_bits")
check_vth_profiles = _core_rule("vth_profiles")
check_compartment_profiles = _core_rule("compartment_profiles")
check_voltage_limits = _core_rule("voltage_limits")

CORE_RULES = (check_compartments, check_input_axons, check_output_axons, check_synapse_bits,
              check_vth_profiles, check_compartment_profiles, check_voltage_limits)


def check_core(core: dict, chip: ChipSpec = LOIHI1) -> list[Violation]:
    """Every per-core design rule applied to one core's usage record (a ``CoreMap`` core dict)."""
    out: list[Violation] = []
    for rule in CORE_RULES:
        out.extend(rule(core, chip))
    return out


def check_delay(layer_name: str, max_delay: int, chip: ChipSpec = LOIHI1) -> list[Violation]:
    """A projection's extra synaptic delay must fit the chip's delay field (0..max_delay steps)."""
    if max_delay <= chip.max_delay and max_delay >= 0:
        return []
    return [Violation("delay", int(max_delay), chip.max_delay, layer=layer_name)]


def check_core_count(n_cores: int, chip: ChipSpec = LOIHI1) -> list[Violation]:
    """A map may span several chips, up to ``max_chips`` when the system has a fixed size."""
    if chip.max_chips is None or n_cores <= chip.max_chips * chip.cores_per_chip:
        return []
    return [Violation("cores", n_cores, chip.max_chips * chip.cores_per_chip,
                      detail=f"{chip.max_chips} chip(s) of {chip.cores_per_chip} cores")]
