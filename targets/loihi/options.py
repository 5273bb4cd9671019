"""Loihi's option record and the constants it shares with the lowering, each defined once, here.

Light on purpose: the registered target (``capabilities.py``) imports this module whenever a command
lists or chooses a target, so it imports nothing but the interface (no numpy). The lowering reads the
same names (``lowering/timing.py``: ``TIMINGS``; ``lowering/scaling.py``: ``SCALE_RULES``;
``lowering/replicate.py``: ``MAX_REPLICAS``; ``lowering/lower.py``: ``COMPILE_OPTIONS``), so a choice
the command line offers is the choice the lowering accepts.

    LoihiOptions       what a user sets (``--timing``, ``--scale``, ``--replicas``, ...): the validated
                       record reaches lowering, checks and fine-tuning as it is
    LoihiStudyKnobs    what only benches and studies set (fine-tuning's learned parameters, surrogate
                       slope, starting-point search): never an option of a command
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

from snncc.targets.base import TargetOptions, declared_options, option

MODEL_VERBS = ("lower", "check", "agree", "map")   # check and agree compile a model; map refuses them for a bundle
TIMINGS = ("exact", "paper")
SCALE_RULES = ("auto", "global", "per-layer", "split", "fine")
MAX_REPLICAS = 16
STREAM_GAP = 100                   # blank steps between samples in stream mode (the paper's protocol)
# the options compile records in the bundle (/snncc/metadata compile_options): what check lowers again with
COMPILE_OPTIONS = ("timing", "scale", "allow_reset_change", "time_steps", "replicas")
LEARNED = ("weights", "thresholds", "decays", "biases")   # what fine-tuning trains by default


@dataclass(frozen=True)
class LoihiOptions(TargetOptions):
    """Loihi's options (each declared for the verbs that read it)."""

    timing: str | None = option(
        "Timing: 'exact' (default) lowers the IR's delays and refractory period; 'paper' reproduces the "
        "authors' export (refDelay 1, no delays).", choices=TIMINGS, rule=f"timing must be one of {TIMINGS}",
        capabilities=MODEL_VERBS)
    scale: str | None = option(
        "Weight scale rule: 'global' (the paper's), 'per-layer', 'split' (per-layer, outlier weights in a "
        "second synapse format with a coarser exponent), 'fine' (each synapse its finest exponent), or 'auto' "
        "(default: the paper's unless outliers make it lossy; then the candidate with the smallest measured error).",
        choices=SCALE_RULES, rule="scale must be one of global, per-layer, split, fine, auto", capabilities=MODEL_VERBS)
    replicas: int | None = option(
        "Precision by replication: K relays per input channel and K copies of every hidden neuron, each weight "
        "split over K synapses (exact in float; K times finer weight steps at per-neuron scales, e.g. with "
        "--finetune; costs neurons, synapses and one step of latency). Default 1.",
        minimum=1, maximum=MAX_REPLICAS, rule=f"replicas must be a whole number from 1 to {MAX_REPLICAS}",
        capabilities=MODEL_VERBS)
    allow_reset_change: bool = option(
        "Accept a subtract-reset model deployed with reset to zero (snncc check reports the cost).",
        default=False, capabilities=("lower", "check", "agree"))
    stream: bool = option("The paper's protocol, one stream with 100 blank steps between samples.",
                          default=False, capabilities=("check",))
    time_steps: int | None = option("tSample (default: the model's recording length / dt, else snncc's 256).",
                                    minimum=1, rule="time steps must be a whole number >= 1", capabilities=("lower",))

    @property
    def timing_mode(self) -> str:
        """The timing lowered: ``timing``, else "exact"."""
        return self.timing or "exact"

    @property
    def scale_rule(self) -> str:
        """The scale rule asked for: ``scale``, else "auto"."""
        return self.scale or "auto"

    def compile_record(self) -> dict[str, object]:
        """What the bundle records of the options it was compiled with (``COMPILE_OPTIONS``, None where not given)."""
        return {key: getattr(self, key) for key in COMPILE_OPTIONS}


def recorded(values: Mapping[str, object]) -> LoihiOptions:
    """The ``LoihiOptions`` a bundle records (``COMPILE_OPTIONS`` of /snncc/metadata ``compile_options``), each
    value validated by its declaration as a user's would be (a one-line refusal otherwise)."""
    declared = declared_options(LoihiOptions)
    given: dict[str, object] = {}
    for key in COMPILE_OPTIONS:
        value = values.get(key)
        if key == "allow_reset_change":
            value = bool(value)
        if value is not None:
            given[key] = declared[key].parse(value)
    build: Callable[..., LoihiOptions] = LoihiOptions
    return build(**given)


@dataclass(frozen=True)
class LoihiStudyKnobs:
    """Settings only benches and studies change (``finetune.run.finetune_loihi``): which registers fine-tuning
    learns, the surrogate gradient's slope, and whether the starting points are searched first."""

    learn: tuple[str, ...] = LEARNED
    slope: float = 5.0
    search: bool = True


__all__ = ["LoihiOptions", "LoihiStudyKnobs", "TIMINGS", "SCALE_RULES", "MAX_REPLICAS", "STREAM_GAP",
           "COMPILE_OPTIONS", "MODEL_VERBS", "LEARNED"]
