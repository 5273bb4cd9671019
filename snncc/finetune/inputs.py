"""The unlabelled inputs fine-tuning learns from, and their train / validation / held-out split.

    the user's data    (N, T, C) 0/1 spikes (labels optional: only used to REPORT task accuracy on the
                       held-out part, never to train); its density = mean spikes per channel and step
    otherwise          seeded synthetic spikes: every entry 1 with probability ``density``
                       (default 0.08, or the density estimated from ``density_from`` data), SYNTHETIC

Split (seeded permutation): the last ``held_out`` samples measure the result and are never trained
on or used for choices; ``validation`` samples before them pick the kept parameters; the rest train.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from snncc.errors import SnnccError

DEFAULT_DENSITY = 0.08
DEFAULT_TRAIN = 2048
DEFAULT_VALIDATION = 500
DEFAULT_HELD_OUT = 1000
MIN_VALIDATION = 128          # floors of the parts that scale with the training samples: 128 validation samples
MIN_HELD_OUT = 256            # tell a paired gain of about 10 points; 256 held-out give an interval of about +-0.06


def synthetic_sizes(train: int) -> tuple[int, int]:
    """(validation, held-out) samples for ``train`` seeded training samples: in the default's proportions (2,048 ->
    500 and 1,000), never below ``MIN_VALIDATION`` and ``MIN_HELD_OUT``."""
    return (max(MIN_VALIDATION, round(train * DEFAULT_VALIDATION / DEFAULT_TRAIN)),
            max(MIN_HELD_OUT, round(train * DEFAULT_HELD_OUT / DEFAULT_TRAIN)))


@dataclass
class Split:
    """Inputs split three ways (index arrays into ``x``), with their description for the record."""

    x: np.ndarray                 # (N, T, C) uint8
    labels: np.ndarray | None     # (N,) or None
    train: np.ndarray
    validation: np.ndarray
    held_out: np.ndarray
    source: str                   # "data" | "synthetic"
    description: str
    density: float
    seed: int

    def as_dict(self) -> dict:
        return {"source": self.source, "description": self.description, "density": self.density, "seed": self.seed,
                "steps": int(self.x.shape[1]), "channels": int(self.x.shape[2]), "train": int(self.train.size),
                "validation": int(self.validation.size), "held_out": int(self.held_out.size),
                "labels": self.labels is not None}


def spike_density(x: np.ndarray) -> float:
    """Mean spikes per channel and step of (N, T, C) 0/1 data."""
    return float(np.mean(np.asarray(x, np.float64)))


def synthetic_spikes(samples: int, steps: int, width: int, density: float, seed: int) -> np.ndarray:
    """(samples, steps, width) uint8, each entry 1 with probability ``density`` (numpy's default_rng(seed))."""
    if not (isinstance(density, (int, float)) and 0.0 < float(density) <= 1.0):
        raise SnnccError(f"spike density must be in (0, 1], got {density}", field="--density")
    return (np.random.default_rng(seed).random((samples, steps, width)) < float(density)).astype(np.uint8)


def _check_data(x, width: int, steps: int | None, source: str | None) -> np.ndarray:
    x = np.asarray(x)
    if x.ndim != 3:
        raise SnnccError(f"inputs must be (N, T, C), got shape {x.shape}", file=source, field="inputs")
    if x.shape[2] != width:
        raise SnnccError(f"inputs have {x.shape[2]} channels, the model takes {width}", file=source, field="inputs")
    if steps is not None and x.shape[1] != steps:
        raise SnnccError(f"inputs have {x.shape[1]} steps, the model runs {steps}", file=source, field="inputs")
    if x.dtype.kind not in "biuf" or not np.all((x == 0) | (x == 1)):
        raise SnnccError("inputs must be 0/1 spikes", file=source, field="inputs")
    return x.astype(np.uint8)


def split_inputs(*, width: int, steps: int, data=None, labels=None, density: float | None = None,
                 density_from=None, train: int = DEFAULT_TRAIN, validation: int = DEFAULT_VALIDATION,
                 held_out: int = DEFAULT_HELD_OUT, seed: int = 0, source: str | None = None) -> Split:
    """The inputs of one fine-tuning run (see the module docstring). With ``data``, ``train`` is
    whatever is left after ``validation`` and ``held_out`` (at least one sample each)."""
    for name, value in (("validation", validation), ("held_out", held_out), ("train", train)):
        if not (isinstance(value, (int, np.integer)) and value >= 1):
            raise SnnccError(f"must be a whole number >= 1, got {value}", field=name)
    if data is not None:
        x = _check_data(data, width, None, source)
        n = x.shape[0]
        if n < validation + held_out + 1:
            raise SnnccError(f"{n} samples cannot give {held_out} held-out, {validation} validation and at least one "
                             "training sample", file=source, field="inputs")
        if labels is not None:
            labels = np.asarray(labels)
            if labels.shape != (n,):
                raise SnnccError(f"labels must be ({n},), got {labels.shape}", file=source, field="labels")
        order = np.random.default_rng(seed).permutation(n)
        d = spike_density(x)
        return Split(x, labels, order[:n - validation - held_out], order[n - validation - held_out:n - held_out],
                     order[n - held_out:], "data", f"{n} given samples of {x.shape[1]} steps (density {d:.4f})",
                     d, seed)
    if density is None:
        density = spike_density(_check_data(density_from, width, None, source)) if density_from is not None \
            else DEFAULT_DENSITY
        if not density > 0:
            raise SnnccError("the data has no spikes to estimate a density from", file=source, field="--density")
    n = train + validation + held_out
    x = synthetic_spikes(n, steps, width, density, seed)
    idx = np.arange(n)
    return Split(x, None, idx[:train], idx[train:train + validation], idx[train + validation:], "synthetic",
                 f"{n} seeded random spike trains (density {density:g}, seed {seed}), {steps} steps (SYNTHETIC)",
                 float(density), seed)


def model_split(graph, inputs=None, labels=None, *, time_steps: int | None = None, density: float | None = None,
                samples: int = DEFAULT_TRAIN, seed: int = 0, data: str | None = None) -> Split:
    """The split a target's ``finetune`` capability learns from (``FinetuneOptions``): the user's ``inputs``
    (read from ``data``; a quarter held out, at most 1,000, an eighth for validation, at most 500, the rest
    trains; their steps must match ``time_steps`` when given), else ``samples`` seeded random training spike trains
    of ``density`` and the model's steps (``snncc.ir.timebase.sample_steps``) and validation and held-out parts in
    proportion (``synthetic_sizes``: 500 and 1,000 for the default 2,048)."""
    from snncc.ir.nodes import Input
    from snncc.ir.timebase import sample_steps

    width = sum(int(graph.node(n).width) for n in graph.of_kind(Input))
    if inputs is not None:
        x = np.asarray(inputs)
        if x.ndim == 3 and time_steps is not None and int(time_steps) != x.shape[1]:
            raise SnnccError(f"the data has {x.shape[1]} steps per sample, --time-steps says {time_steps}",
                             file=data, field="--time-steps")
        n = int(x.shape[0]) if x.ndim else 0
        return split_inputs(width=width, steps=int(x.shape[1]) if x.ndim == 3 else 0, data=x, labels=labels,
                            validation=min(DEFAULT_VALIDATION, max(1, n // 8)),
                            held_out=min(DEFAULT_HELD_OUT, max(1, n // 4)), seed=seed, source=data)
    steps, _ = sample_steps(graph, time_steps)
    validation, held_out = synthetic_sizes(int(samples))
    return split_inputs(width=width, steps=steps, density=density, train=samples, validation=validation,
                        held_out=held_out, seed=seed)
