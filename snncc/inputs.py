"""Arrays a user feeds a model (``emulate``, ``run``, ``check``), checked before anything runs.

One rule set for every verb: inputs are (T, C) or (B, T, C) with B >= 1 samples, 1 <= T <=
``MAX_TIME_STEPS`` steps and C channels; numeric and finite; spike inputs hold only 0 and 1.
Labels are N integers in 0..n_classes-1.
"""

from __future__ import annotations

import numpy as np

from snncc.errors import SnnccError
from snncc.limits import check_time_steps


def check_batch(x, width: int | None = None, *, spikes: bool = True, source: str | None = None,
                field: str = "input") -> np.ndarray:
    """(T, C) or (B, T, C) -> (B, T, C), refusing empty axes, wrong widths, NaN/Inf and, for
    ``spikes``, any value other than 0 and 1. The array keeps its dtype."""
    x = np.asarray(x)
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3:
        raise SnnccError(f"input must have shape (T, C) or (B, T, C), got {x.shape}", file=source, field=field)
    if x.dtype.kind not in "biuf":
        raise SnnccError(f"input must be numeric{' 0/1 values' if spikes else ''}, got dtype {x.dtype}",
                         file=source, field=field)
    if x.shape[0] < 1:
        raise SnnccError("the batch is empty (B = 0 samples); give at least one sample", file=source, field=field)
    check_time_steps(x.shape[1], f"the input's time axis (shape {x.shape})", file=source, field=field)
    if width is not None and x.shape[2] != width:
        raise SnnccError(f"input has {x.shape[2]} channels, the model's input layer has {width}",
                         file=source, field=field)
    if x.dtype.kind == "f" and not np.all(np.isfinite(x)):
        raise SnnccError("input contains NaN or Inf" + ("; spikes must be 0 or 1" if spikes else ""),
                         file=source, field=field)
    if spikes and not np.all((x == 0) | (x == 1)):
        bad = x[(x != 0) & (x != 1)].reshape(-1)[0].item()
        raise SnnccError(f"input must be binary (0/1 spikes), found the value {bad!r}", file=source, field=field)
    return x


def check_labels(labels, n_samples: int, n_classes: int | None, *, source: str | None = None,
                 field: str = "labels") -> np.ndarray:
    """N = ``n_samples`` integer labels, each in 0..n_classes-1 (the model's classes)."""
    y = np.asarray(labels)
    if y.ndim != 1 or y.shape[0] != n_samples or y.dtype.kind not in "iu":
        raise SnnccError(f"labels must be N = {n_samples} integers", file=source, field=field)
    if n_samples < 1:
        raise SnnccError("the data set is empty (N = 0 samples)", file=source, field=field)
    if n_classes is not None and y.size and (y.min() < 0 or y.max() >= n_classes):
        bad = int(y[(y < 0) | (y >= n_classes)][0])
        raise SnnccError(f"label {bad} is outside the model's {n_classes} classes (0..{n_classes - 1})",
                         file=source, field=field)
    return y


def model_classes(graph) -> int | None:
    """How many classes a graph decides between: its single Output's width (None if it has several)."""
    from snncc.ir.nodes import Output

    outs = graph.of_kind(Output)
    return graph.node(outs[0]).size if len(outs) == 1 else None


def check_dataset(inputs, labels, graph, *, source: str | None = None) -> None:
    """A labelled data set for ``graph``: N >= 1 samples of T >= 1 steps, labels within its classes."""
    x = check_batch(inputs, spikes=False, source=source, field="inputs")
    check_labels(labels, x.shape[0], model_classes(graph), source=source)


# -- input files and seeded random inputs ----------------------------------------------------------
def load_array(path, field: str = "--input") -> np.ndarray:
    """A .npy array (no pickles), or a .npz data set's ``inputs`` array (what ``snncc data`` writes and
    ``check --data`` reads: every verb takes the same files)."""
    import zipfile
    import zlib
    from pathlib import Path

    path = Path(path)
    if not path.is_file():
        raise SnnccError("file does not exist", file=str(path), field=field)
    try:
        obj = np.load(path, allow_pickle=False)
        if not isinstance(obj, np.lib.npyio.NpzFile):
            return obj
        with obj:
            if "inputs" not in obj.files:
                raise SnnccError(f"a .npz input needs an 'inputs' array (has {sorted(obj.files)})", file=str(path),
                                 field="inputs")
            return obj["inputs"]
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as ex:   # not .npy / a broken .npz
        raise SnnccError(f"not a readable .npy/.npz array ({type(ex).__name__})", file=str(path), field=field) from None


class RandomSpikes:
    """Seeded random 0/1 inputs, drawn once the shape is known: each entry is 1 with probability
    ``rate`` (numpy's default_rng(seed).random(shape) < rate)."""

    def __init__(self, samples: int, rate: float, seed: int):
        self.samples, self.rate, self.seed = samples, rate, seed

    def draw(self, steps: int, width: int) -> np.ndarray:
        """(samples, steps, width) uint8, refusing a bad rate or count and more memory than allowed."""
        from snncc.limits import check_memory

        if not 0.0 <= self.rate <= 1.0 or self.samples < 1:
            raise SnnccError("need 0 <= --rate <= 1 and --samples >= 1", field="--rate/--samples")
        check_memory(8 * self.samples * steps * width,
                     f"{self.samples:,} random samples of {steps} steps x {width} channels", field="--samples")
        rng = np.random.default_rng(self.seed)
        return (rng.random((self.samples, steps, width)) < self.rate).astype(np.uint8)

    def note(self) -> str:
        return (f"SYNTHETIC: {self.samples} seeded random sparse input samples (rate {self.rate}, seed {self.seed}); "
                "no data given")
