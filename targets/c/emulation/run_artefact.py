"""``snncc emulate`` and ``snncc run`` of a written C artefact: inputs taken in the model's own layout, the
emulator (or the compiled C) run on them, the arrays of the emulate contract.

Batch mode: every sample from ``snn_reset``. Stream mode: one continuous run, ``gap`` blank steps (default 100)
between samples, no reset in between; each sample's outputs are its own steps of that run.

Arrays (``arrays()``): ``output_spikes`` (B, T, N) uint8 (spikes per step, a count where a population fires more
than once per step), ``counts`` (B, N) int64, ``prediction`` (B,) int64 (argmax of the counts, ties to the lowest
index); with ``record="all"`` (emulate only) also ``<population>_spikes``, ``<population>_current`` and
``<population>_voltage`` (B, T, n) int32, in state units (2**-F of the model's units, F in the manifest).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snncc.targets.kit import SnnccError
from snncc.targets.kit.emulation import OutputSpikes

DEFAULT_GAP = 100


def artefact_inputs(written, inputs, source: str | None) -> tuple[np.ndarray, str | None]:  # noqa: ANN001
    """(B, T, C) uint8 inputs in the artefact's layout, and the line saying what was done to them."""
    from snncc.targets.kit.inputs import InputLayout, check_batch, to_artefact_layout

    width = written.network.inputs
    layout = InputLayout.from_record(width, written.layout)
    x, note = to_artefact_layout(np.asarray(inputs), layout)
    x = check_batch(x, width, source=source)
    return (np.asarray(x) != 0).astype(np.uint8), note


def streamed(x: np.ndarray, gap: int) -> np.ndarray:
    """The samples of ``x`` (B, T, C) one after another with ``gap`` blank steps between: (1, B*T + (B-1)*gap, C)."""
    b, t, c = x.shape
    out = np.zeros((1, b * t + (b - 1) * gap, c), np.uint8)
    for i in range(b):
        out[0, i * (t + gap):i * (t + gap) + t] = x[i]
    return out


def unstreamed(y: np.ndarray, samples: int, steps: int, gap: int) -> np.ndarray:
    """Each sample's own steps of a streamed run's (1, total, ...) output: (B, T, ...)."""
    return np.stack([y[0, i * (steps + gap):i * (steps + gap) + steps] for i in range(samples)])


def check_gap(gap: int | None, stream: bool) -> int:
    if gap is not None and not stream:
        raise SnnccError("applies only with --stream", field="--gap")
    value = DEFAULT_GAP if gap is None else gap
    if isinstance(value, bool) or int(value) != value or value < 0:
        raise SnnccError(f"must be a whole number >= 0, got {gap}", field="--gap")
    return int(value)


@dataclass
class CEmulation(OutputSpikes):
    """What ``emulate`` (and, with ``backend``, ``run``) returns (``snncc.targets.base.Emulation``)."""

    extra: dict[str, np.ndarray] = field(default_factory=dict)
    saturated: dict[str, int] = field(default_factory=dict)
    layout_note: str | None = None
    mode: str = "batch"
    backend: str = "emulator"
    sha256: str = ""
    program: str = ""
    timing: dict[str, Any] | None = None        # the Cortex-M4 build in QEMU: instructions per step

    def arrays(self) -> dict[str, np.ndarray]:
        return {**self.output_arrays(), **self.extra}

    def summary(self) -> dict[str, Any]:
        return {"backend": self.backend, "artefact_sha256": self.sha256, "saturated": dict(self.saturated),
                "input_layout": self.layout_note, "program": self.program, "timing": self.timing}

    def lines(self) -> list[str]:
        out = [f"C artefact {self.sha256[:16]}... on {self.backend}" + (f" ({self.program})" if self.program else "")]
        if self.layout_note:
            out.append(f"input: {self.layout_note}")
        if self.timing:
            out.append(f"{self.timing['instructions_per_step']:.0f} instructions per step on average, at most "
                       f"{self.timing['most_instructions_in_a_step']} in one ({self.timing['rule']})")
        if any(self.saturated.values()):
            out.append(f"saturated state updates (clamped to int32): {self.saturated}")
        return out

    def warnings(self) -> list[str]:
        return []

    def as_dict(self) -> dict[str, Any]:
        """``snncc run``'s record."""
        prediction = self.prediction.tolist()
        return {"backend": self.backend, "variant": f"C ({self.program})" if self.program else "C",
                "samples": self.samples, "time_steps": self.steps, "prediction": prediction,
                "classes": [str(p) for p in prediction], "input_layout": self.layout_note, "mode": self.mode,
                "artefact_sha256": self.sha256, "timing": self.timing}


def emulate_artefact(path, inputs, *, record: str = "outputs", stream: bool = False,  # noqa: ANN001
                     gap: int | None = None, source: str | None = None, progress=None) -> CEmulation:
    """``snncc emulate`` of the artefact at ``path`` (module doc)."""
    from snncc.targets.c.artefact.written import open_artefact
    from snncc.targets.c.emulation.emulator import emulate_network
    from snncc.targets.kit.compute import check_memory

    if record not in ("outputs", "all"):
        raise SnnccError("must be 'outputs' or 'all'", field="--record")
    blank = check_gap(gap, stream)
    written = open_artefact(path)
    net = written.network
    x, note = artefact_inputs(written, inputs, source)
    samples, steps = int(x.shape[0]), int(x.shape[1])
    if record == "all":
        check_memory(8 * 3 * samples * steps * sum(p.n for p in net.populations),
                     f"recording every population's state for {samples} samples x {steps} steps", field="--record")
    run = emulate_network(net, streamed(x, blank) if stream else x, record=record == "all", progress=None)
    out = unstreamed(run.output_spikes, samples, steps, blank) if stream else run.output_spikes
    extra: dict[str, np.ndarray] = {}
    for p in net.populations if record == "all" else ():
        for kind, table, dtype in (("spikes", run.spikes, np.uint8), ("current", run.current, np.int32),
                                   ("voltage", run.voltage, np.int32)):
            series = unstreamed(table[p.name], samples, steps, blank) if stream else table[p.name]
            extra[f"{p.name}_{kind}"] = series.astype(dtype)
    if progress is not None:
        progress(samples)
    return CEmulation(out, extra, run.saturated, note, "stream" if stream else "batch", "emulator", written.sha256)


__all__ = ["CEmulation", "emulate_artefact", "artefact_inputs", "streamed", "unstreamed", "check_gap", "DEFAULT_GAP"]
