"""The paper's Jetson protocol, so numbers compare like with like.

Data set and model loaded first; warm-up: predict the whole data set ``warmup_passes`` (6) times
in batches of ``warmup_batch`` (64); timing: predict it ``timed_passes`` (6) times at batch 1;
per-sample time = timed wall time / (passes * samples). The timing is repeated ``repeats`` (3)
times; the report gives the median and the spread (max - min). With a power sampler, each timed
repeat is sampled (INA3221, 50 ms): min / max / average power, and energy per sample = average
power * per-sample time.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from snncc.targets.jetson.power import PowerSampler


@dataclass
class BenchRecord:
    artefact: str
    backend: str
    variant: str
    data: str
    samples: int
    time_steps: int
    protocol: dict
    per_sample_ms: list = field(default_factory=list)       # one figure per repeat
    median_ms: float = 0.0
    spread_ms: float = 0.0
    accuracy: float | None = None
    power: list = field(default_factory=list)               # one record per repeat
    power_summary: dict | None = None
    notes: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return asdict(self)

    def render_text(self, console) -> None:
        console.print(f"[bold]snncc bench[/bold] {self.artefact} ({self.variant}, {self.backend})  data: {self.data}")
        console.print(f"per-sample latency: median {self.median_ms:.3f} ms, spread {self.spread_ms:.3f} ms over "
                      f"{len(self.per_sample_ms)} repeats ({', '.join(f'{v:.3f}' for v in self.per_sample_ms)} ms)")
        if self.accuracy is not None:
            console.print(f"accuracy: {self.accuracy:.2%}")
        if self.power_summary:
            p = self.power_summary
            console.print(f"power ({p['rail']}): min {p['min_mw']:.0f} mW, max {p['max_mw']:.0f} mW, avg "
                          f"{p['avg_mw']:.0f} mW; energy per sample {p['energy_per_sample_uj']:.0f} uJ "
                          f"(spread {p['energy_spread_uj']:.0f})")
        for note in self.notes:
            console.print(f"note: {note}")


def _predict(runner, x: np.ndarray, stream: bool) -> np.ndarray:
    res = runner.stream(x) if stream else runner.run(x)
    return res["prediction"]


def run_protocol(runner, inputs: np.ndarray, labels: np.ndarray | None = None, *, data_label: str = "",
                 warmup_passes: int = 6, warmup_batch: int = 64, timed_passes: int = 6, repeats: int = 3,
                 stream: bool = False, sampler: PowerSampler | None = None,
                 progress: Callable[[str, int], None] | None = None) -> BenchRecord:
    """Run the protocol on ``inputs`` (N, T, C); ``progress(phase, samples_done)`` is called as it goes."""
    x = np.ascontiguousarray(np.asarray(inputs, dtype=np.float32))
    n = x.shape[0]
    tick = progress or (lambda phase, k: None)
    for _ in range(warmup_passes):
        for start in range(0, n, warmup_batch):
            _predict(runner, x[start:start + warmup_batch], stream)
            tick("warm-up", min(warmup_batch, n - start))
    per_sample, powers = [], []
    predictions = np.zeros(n, np.int64)
    for _ in range(repeats):
        if sampler is not None:
            sampler.start()
        t0 = time.perf_counter()
        for _ in range(timed_passes):
            for i in range(n):
                predictions[i] = _predict(runner, x[i:i + 1], stream)[0]
                tick("timing", 1)
        elapsed = time.perf_counter() - t0
        if sampler is not None:
            powers.append(sampler.stop())
        per_sample.append(elapsed / (timed_passes * n))
    ms = [s * 1e3 for s in per_sample]
    record = BenchRecord(
        artefact=runner.directory, backend=runner.session("step" if stream else "sequence").backend,
        variant="step (streaming)" if stream else "sequence", data=data_label, samples=n,
        time_steps=int(x.shape[1]),
        protocol={"warmup_passes": warmup_passes, "warmup_batch": warmup_batch, "timed_passes": timed_passes,
                  "timed_batch": 1, "repeats": repeats},
        per_sample_ms=ms, median_ms=statistics.median(ms), spread_ms=max(ms) - min(ms),
    )
    if labels is not None:
        record.accuracy = float(np.mean(predictions == np.asarray(labels)))
    if powers:
        record.power = [
            {**asdict(p), "energy_per_sample_uj": p.energy_uj(s)} for p, s in zip(powers, per_sample)
        ]
        energies = [r["energy_per_sample_uj"] for r in record.power]
        record.power_summary = {
            "rail": powers[0].rail,
            "min_mw": min(p.min_mw for p in powers),
            "max_mw": max(p.max_mw for p in powers),
            "avg_mw": statistics.median(p.avg_mw for p in powers),
            "energy_per_sample_uj": statistics.median(energies),
            "energy_spread_uj": max(energies) - min(energies),
        }
    return record


@dataclass
class LatencyComparison:
    """Several artefacts timed with the same protocol in one run; ratios to the first one's median."""

    records: list = field(default_factory=list)     # BenchRecord per artefact, in the order given
    kinds: list = field(default_factory=list)

    def ratios(self) -> list[float]:
        ref = self.records[0].median_ms if self.records else float("nan")
        return [r.median_ms / ref if ref > 0 else float("nan") for r in self.records]

    def as_dict(self) -> dict:
        return {"reference": self.records[0].artefact if self.records else None,
                "models": [{"kind": k, "ratio_to_reference": q, **r.as_dict()}
                           for k, q, r in zip(self.kinds, self.ratios(), self.records)]}

    def table(self) -> str:
        """A markdown table; its ``inputs`` column says which inputs were SYNTHETIC (seeded random)."""
        lines = ["| artefact | kind | variant | backend | input (T x C) | inputs | median ms / sample | spread ms | x first |",
                 "|---|---|---|---|---|---|---|---|---|"]
        for k, q, r in zip(self.kinds, self.ratios(), self.records):
            lines.append(f"| {r.artefact} | {k} | {r.variant} | {r.backend} | {r.time_steps} x {r.protocol.get('channels')} | "
                         f"{inputs_kind(r.data)} | {r.median_ms:.3f} | {r.spread_ms:.3f} | {q:.2f} |")
        return "\n".join(lines) + "\n"

    def render_text(self, console) -> None:
        console.print(self.table(), markup=False, soft_wrap=True)
        console.print("note: batch-1 latency, the paper's protocol; ratios are to the first artefact; power not sampled",
                      soft_wrap=True)
        if any(r.data.startswith("SYNTHETIC") for r in self.records):
            console.print("note: inputs SYNTHETIC (random): seeded random inputs of the artefact's shape (no --data, "
                          "or a data set that does not fit it); the latency is measured, there is no accuracy",
                          soft_wrap=True)


def inputs_kind(data_label: str) -> str:
    """A bench record's inputs in one word or two: SYNTHETIC (seeded random), or the data set's kind."""
    if data_label.startswith("SYNTHETIC inputs"):
        return "SYNTHETIC (random)"
    return "data set (SYNTHETIC)" if "synthetic data" in data_label.lower() else "data set (recorded)"


def compare_protocol(entries: list, progress: Callable[[str, int], None] | None = None, **protocol) -> LatencyComparison:
    """``entries``: (runner, inputs, labels, data_label) per artefact; each is run with ``run_protocol``."""
    out = LatencyComparison()
    for runner, inputs, labels, label in entries:
        name = Path(runner.directory).name
        tick = None if progress is None else (lambda phase, k, name=name: progress(f"{name}: {phase}", k))
        record = run_protocol(runner, inputs, labels, data_label=label, progress=tick, **protocol)
        record.protocol["channels"] = int(np.asarray(inputs).shape[2])
        out.records.append(record)
        out.kinds.append(runner.manifest["model"]["kind"])
    return out
