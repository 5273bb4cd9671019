"""Xylo's option record (``XyloOptions``: what a user sets), the knobs only benches and studies turn
(``XyloStudyKnobs``), and the constants both read: each defined here once.

The record is validated by ``snncc.targets.base.target_options`` when a verb builds it and reaches the
lowering and fine-tuning as it is. Nothing here imports anything heavy (not even numpy): the entry
module (``capabilities.py``) imports it when a command lists or chooses a target.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from snncc.targets.base import TargetOptions, option
from snncc.targets.xylo.chip import CHIPS, DEFAULT_CHIP

CHIP_KEYS = tuple(CHIPS)                                               # --chip
RULES = ("auto", "direct", "single", "single-identified", "relayed")   # --rule
MAX_REPLICAS = 8                 # --replicas: copies of the hidden network (each calibrated on its own inputs)
RELAY_SETS = ("fast", "both")    # --relays: one relay set per source at the faster dash, or one at each dash
MODEL_VERBS = ("lower", "check", "agree", "map")

DEFAULT_CALIBRATION_SAMPLES = 256
BOTH_CALIBRATION_SAMPLES = 1024  # --relays both: twice the relay columns to fit (Braille RSNN, 4 replicas: 256 samples
                                 # 0.849, 1024 samples 0.856 pooled over 7,272 held-out samples; docs/xylo_lowering.md)
DEFAULT_DENSITY = 0.08           # spike density of the seeded calibration inputs
DEFAULT_SEED = 1                 # seed of the calibration inputs (a setting no flag offers)


@dataclass(frozen=True)
class XyloOptions(TargetOptions):
    """Xylo's options (each declared for the verbs that read it); ``seed`` (of the calibration inputs) is a
    setting no flag offers."""

    chip: str | None = option(
        "Xylo chip: 'syns61201' (Xylo Audio 2, default), 'syns63300' (Xylo IMU), 'syns65302' (Xylo Audio 3).",
        choices=CHIP_KEYS, rule=f"chip must be one of {', '.join(CHIP_KEYS)}", capabilities=MODEL_VERBS)
    rule: str | None = option(
        "Xylo placement rule: 'direct' (one chip neuron per neuron, nearest decays), 'single' (two synaptic "
        "currents fitted to the neuron's kernel, one spike per step), 'single-identified' (the same, weights fitted "
        "to the float graph's voltages), 'relayed' (the same with sigma-delta relay neurons adding a third kernel "
        "term), or 'auto' (default: each measured in snncc's emulator, the best kept).",
        choices=RULES, rule=f"rule must be one of {', '.join(RULES)}", capabilities=MODEL_VERBS)
    replicas: int | None = option(
        "Replicas of the hidden network, each fitted and rounded on its own calibration inputs (its relays a step "
        "coarser), the output neurons reading each with 1/K of the weights: the copies' rounding errors partly "
        "average out (costs K times the hidden neurons and their synaptic events). Default 1.",
        minimum=1, maximum=MAX_REPLICAS, rule=f"replicas must be a whole number from 1 to {MAX_REPLICAS}",
        capabilities=MODEL_VERBS)
    relays: str | None = option(
        "Relays of the relayed rule: 'fast' (default: one sigma-delta relay per presynaptic channel, at the faster "
        "synapse dash) or 'both' (two, one at each synapse dash: a finer kernel fit, fitted on 1024 calibration "
        "samples unless --calibration-samples says otherwise; costs a second relay neuron per channel, twice the "
        "relays' events and a lowering several times slower).",
        choices=RELAY_SETS, rule=f"relays must be one of {', '.join(RELAY_SETS)}", capabilities=MODEL_VERBS)
    allow_reset_change: bool = option(
        "Accept a model that resets to zero, deployed with reset by subtraction (Xylo's; snncc check measures the "
        "cost).", default=False, capabilities=("lower", "check", "agree"))
    time_steps: int | None = option("Steps of a sample: each seeded calibration sample's (the artefact records them; "
                                    "check and report draw their random samples that long). Default: the model's "
                                    "recording length / dt, else snncc's default.", minimum=1,
                                    rule="time steps must be a whole number >= 1", capabilities=("lower",))
    calibration_samples: int | None = option(
        "Seeded random calibration samples the rule is fitted and chosen on (default 256, 1024 with --relays both; "
        "SYNTHETIC).", minimum=2,
        rule="calibration samples must be a whole number >= 2", capabilities=("lower",))
    seed: int = DEFAULT_SEED

    # -- the values the lowering reads (defaults applied) -------------------------------------------------
    @property
    def chip_key(self) -> str:
        return self.chip or DEFAULT_CHIP

    @property
    def placement_rule(self) -> str:
        return self.rule or "auto"

    @property
    def copies(self) -> int:
        return 1 if self.replicas is None else int(self.replicas)

    @property
    def both_relays(self) -> bool:
        """``--relays both`` (relays at both synapse dashes); "fast" or not given: one set at the faster dash."""
        return (self.relays or "fast") == "both"


@dataclass(frozen=True)
class XyloStudyKnobs:
    """What only benches and studies set, beside the user's ``XyloOptions`` (never a flag):

    ``calibration``: the calibration inputs, (B, T, C) 0/1 spikes (instead of seeded random ones);
    ``density``: spike density of the seeded calibration inputs (default ``DEFAULT_DENSITY``);
    ``emulator``: ``(spec dict, chip inputs) -> output spikes`` that measures the candidates (default: snncc's
    bit-exact emulator); ``rounding``: "none" leaves every weight unrounded (a float spec in chip units that only
    the float twin runs: what rounding costs, bench/studies/xylo_loss_sources.py; it needs ``emulator``, and such a spec
    is neither checked against the chip's rules nor estimated for real time); ``refit``: fit the chosen rule again
    on every calibration sample (default True); ``readout``: only the candidates with the readout on the "output"
    neurons or on "hidden" neurons copied to them (default: every candidate)."""

    calibration: Any = None
    density: float | None = None
    emulator: Callable[..., Any] | None = None
    rounding: str | None = None
    refit: bool = True
    readout: str | None = None


NO_KNOBS = XyloStudyKnobs()

__all__ = ["XyloOptions", "XyloStudyKnobs", "NO_KNOBS", "CHIP_KEYS", "RULES", "MAX_REPLICAS", "RELAY_SETS",
           "MODEL_VERBS", "DEFAULT_CALIBRATION_SAMPLES", "BOTH_CALIBRATION_SAMPLES", "DEFAULT_DENSITY",
           "DEFAULT_SEED"]
