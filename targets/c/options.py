"""The C target's option record and its constants, defined once (the lowering, emulator, code generator and
estimate import them from here). Imports nothing heavy.

The arithmetic (docs/c.md):

    state        int32 current I and voltage V per neuron, in units of 2**-F of the model's units, F per population
                 chosen so the largest threshold is 2**THRESHOLD_BITS .. 2**(THRESHOLD_BITS+1) units
    weights      int8 (or int16) with power-of-two scales 2**e (e >= 0 in state units), one per projection
                 ("per-layer") or per projection and target neuron ("per-neuron")
    decays       alpha, beta as Q.DECAY_BITS fixed-point multipliers; product rounded half up:
                 floor((a * x + 2**(DECAY_BITS-1)) / 2**DECAY_BITS)
    saturation   every state update is computed exactly in 64 bits, then clamped to the int32 range
"""

from __future__ import annotations

from dataclasses import dataclass

from snncc.targets.base import TargetOptions, option
from snncc.targets.c.estimate.parts import DEFAULT_PART, PART_KEYS

RULES = ("auto", "per-layer", "per-neuron", "per-layer-16", "per-neuron-16")
CANDIDATES = RULES[1:]                   # what ``auto`` measures
RULE_BITS = {"per-layer": 8, "per-neuron": 8, "per-layer-16": 16, "per-neuron-16": 16}
WEIGHT_LIMIT = {8: 127, 16: 32767}       # symmetric: -limit .. limit
DECAY_BITS = 16                          # alpha, beta in Q16 (products of int32 states stay below 2**47)
THRESHOLD_BITS = 20                      # the largest threshold of a population lies in [2**20, 2**21) units
MAX_EXPONENT = 30                        # weight scale 2**e, 0 <= e <= 30
MAX_DELAY = 255                          # steps an edge path may delay (ring buffers of up to 256 slots)
MAX_SPIKES = 255                         # spikes one neuron may emit per step (an event's count is a uint8)
COUNT_LIMIT = 65535                      # out_counts saturate here (uint16_t)
INPUT_COUNTS = 1                         # an input channel delivers at most one spike per step (0/1 inputs)
MODEL_VERBS = ("lower", "check", "agree", "map")
CALIBRATION_SAMPLES = 512                # seeded random samples ``auto`` measures its candidates on
CALIBRATION_DENSITY = 0.08
CALIBRATION_SEED = 7
AUTO_P = 0.05                            # ``auto`` takes a wider or finer rule only when it agrees better by a
                                         # paired sign test at this one-sided p (kit.agreement.sign_test)
VALIDATION_SAMPLES = 16                  # seeded samples ``lower`` runs the re-read artefact on
BACKENDS = ("auto", "host", "qemu")
CPI = {"Cortex-M4 (FPU)": 1.5, "Cortex-M0+": 1.5}    # cycles per instruction assumed (an ESTIMATE; docs/c.md)
FORMAT = "snncc-c-artefact"
VERSION = 1


@dataclass(frozen=True)
class COptions(TargetOptions):
    """The C target's options (each declared for the verbs that read it); ``seed`` (of the calibration inputs) is a
    setting no flag offers."""

    rule: str | None = option(
        "C target weight rule: 'per-layer' (int8, one power-of-two scale per projection), 'per-neuron' (int8, one "
        "per projection and target neuron), 'per-layer-16' / 'per-neuron-16' (the same in int16: twice the weight "
        "flash), or 'auto' (default: per-neuron int8 unless a finer or wider rule agrees better with the float graph "
        "on seeded calibration inputs by a paired sign test at p < 0.05).",
        choices=RULES, rule=f"rule must be one of {', '.join(RULES)}", capabilities=MODEL_VERBS)
    mcu: str | None = option(
        f"C target: the microcontroller flash, RAM and time per step are reported against: {', '.join(PART_KEYS)} "
        f"(default {DEFAULT_PART}; docs/c.md lists each with its datasheet).",
        choices=PART_KEYS, rule=f"mcu must be one of {', '.join(PART_KEYS)}", capabilities=("lower", "map"))
    time_steps: int | None = option("Steps per sample (default: the model's recording length / dt, else snncc's "
                                    "default).", minimum=1, rule="time steps must be a whole number >= 1",
                                    capabilities=("lower",))
    seed: int = CALIBRATION_SEED


__all__ = ["COptions", "RULES", "CANDIDATES", "RULE_BITS", "WEIGHT_LIMIT", "DECAY_BITS", "THRESHOLD_BITS",
           "MAX_EXPONENT", "MAX_DELAY", "MAX_SPIKES", "COUNT_LIMIT", "MODEL_VERBS", "CALIBRATION_SAMPLES",
           "CALIBRATION_DENSITY", "CALIBRATION_SEED", "AUTO_P", "VALIDATION_SAMPLES", "BACKENDS", "CPI", "FORMAT",
           "VERSION", "PART_KEYS", "DEFAULT_PART"]
