"""``snncc emulate`` of a Xylo artefact: the model's inputs fed to the chip as the manifest says, in
snncc's bit-exact emulator.

Inputs (T, C) or (B, T, C) event counts in the model's time. Each sample gets ``input_pad`` zero steps
before it and zeros after, to ``T + output_lag`` chip steps, and its outputs are the chip's steps
``output_lag .. output_lag + T - 1`` (the model's steps 0 .. T - 1). Stream mode: the samples with
``gap`` zero steps between them run as one continuous chip run (no state reset), then cut apart the
same way. Arrays: ``output_spikes`` (B, T, Nout) uint8 counts, ``counts`` (B, Nout), ``prediction``
(B,) (argmax, ties to the lowest index); record "all" adds the chip's states over the same steps:
``vmem``, ``isyn``, ``isyn2``, ``spikes`` (hidden), ``vmem_out``, ``isyn_out``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.emulation import OutputSpikes
from snncc.targets.xylo.artefact.read import WrittenXylo, read_artefact
from snncc.targets.xylo.emulation.result import STATE_NAMES

DEFAULT_GAP = 100


@dataclass
class XyloEmulation(OutputSpikes):
    states: dict[str, np.ndarray] = field(default_factory=dict)
    input_pad: int = 0
    output_lag: int = 0
    clipped_inputs: int = 0

    @property
    def overflow(self) -> dict[str, int]:
        return {"input_events_clipped_to_15": self.clipped_inputs}

    def summary(self) -> dict[str, object]:
        return {"overflow": self.overflow, "feed": {"input_pad": self.input_pad, "output_lag": self.output_lag}}

    def lines(self) -> list[str]:
        return [f"fed with {self.input_pad} zero step(s) before each sample, outputs read {self.output_lag} step(s) "
                f"later (the artefact's feed); input events clipped to 15: {self.clipped_inputs}"]

    def warnings(self) -> list[str]:
        return []

    def arrays(self) -> dict[str, np.ndarray]:
        return {**self.output_arrays(), **self.states}


def artefact_inputs(x: np.ndarray, n_in: int, source: str | None) -> np.ndarray:
    """(T, C) or (B, T, C) whole event counts >= 0 for an artefact of ``n_in`` input channels -> (B, T, C)."""
    x = np.asarray(x)
    if x.ndim == 2:
        x = x[None]
    if x.ndim != 3 or x.shape[2] != n_in:
        raise SnnccError(f"inputs must be (T, {n_in}) or (B, T, {n_in}) event counts, got shape {tuple(np.shape(x))}",
                         file=source, field="--input")
    if x.dtype == bool:
        x = x.astype(np.uint8)
    if not np.issubdtype(x.dtype, np.number) or (x.size and (not np.all(np.isfinite(x)) or np.any(x < 0)
                                                             or np.any(x != np.floor(x)))):
        raise SnnccError("inputs must be whole event counts >= 0", file=source, field="--input")
    if x.shape[1] < 1 or x.shape[0] < 1:
        raise SnnccError("inputs need at least one sample and one step", file=source, field="--input")
    return x


def emulate_written(written: WrittenXylo, x: np.ndarray, *, record: bool = False, stream: bool = False,
                    gap: int | None = None, source: str | None = None) -> XyloEmulation:
    from snncc.targets.xylo.emulation.emulator import emulate

    spec = written.runnable().spec
    x = artefact_inputs(x, spec.n_in, source)
    b, t, c = x.shape
    pad, lag = written.input_pad, written.output_lag
    clipped = int(np.sum(x > 15))
    x = np.minimum(x, 255).astype(np.uint8)     # the chip clips counts to 15 itself; uint8 keeps counts above 15
    total = t + max(pad, lag)
    if stream:
        gap = DEFAULT_GAP if gap is None else int(gap)
        if gap < 0:
            raise SnnccError("must be >= 0", field="--gap")
        period = t + gap
        run = np.zeros((1, pad + b * period + max(0, lag - pad), c), np.uint8)
        for i in range(b):
            run[0, pad + i * period:pad + i * period + t] = x[i]
        res = emulate(spec, run, record=record)
        starts = [lag + i * period for i in range(b)]
        cut = lambda a: np.stack([a[0, s:s + t] for s in starts])   # noqa: E731
    else:
        if gap is not None:
            raise SnnccError("applies only with --stream", field="--gap")
        run = np.zeros((b, total, c), np.uint8)
        run[:, pad:pad + t] = x
        res = emulate(spec, run, record=record)
        cut = lambda a: a[:, lag:lag + t]   # noqa: E731
    states = {name: cut(getattr(res, name)) for name in STATE_NAMES} if record else {}
    return XyloEmulation(cut(res.output_spikes), states, pad, lag, clipped)


def emulate_artefact(path: Path, x: np.ndarray, *, record: str = "outputs", stream: bool = False,
                     gap: int | None = None, source: str | None = None, progress=None) -> XyloEmulation:
    found = emulate_written(read_artefact(path), x, record=record == "all", stream=stream, gap=gap, source=source)
    if progress is not None:
        progress(found.samples)
    return found
