"""``snncc data synth`` as a function: the SYNTHETIC Braille set in the published Zenodo formats."""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Iterable

from snncc.errors import one_line
from snncc.verbs import VerbProgress

if TYPE_CHECKING:
    from rich.console import Console


@dataclass
class SynthResult:
    """What was written: directory, sample and frame counts, file names, mean events per taxel and
    sample for each threshold (key ``f"{th:g}"``), seed, release, generator version."""

    out: str
    samples: int
    frames: int
    files: list[str]
    mean_events_per_taxel: dict[str, float]
    seed: int
    release: int
    synthetic: bool = True
    generator_version: int = 2

    def as_dict(self) -> dict:
        """What ``snncc data synth --json`` prints."""
        return asdict(self)

    def render_text(self, console: Console) -> None:
        console.print(f"wrote {self.samples} synthetic samples ({self.samples // 27} x 27 letters, seed {self.seed}) "
                      f"to {one_line(self.out)}", markup=False)
        console.print("mean events per taxel and sample: "
                      + ", ".join(f"th {k}: {v:.1f}" for k, v in self.mean_events_per_taxel.items()))


def data_synth(*, out: str | os.PathLike, repetitions: int = 200, seed: int = 0, release: int = 1,
               thresholds: str | Iterable[float] = "1,2,5,10", generator_version: int = 2,
               progress: VerbProgress | None = None) -> SynthResult:
    """Generate 27 x ``repetitions`` synthetic samples into ``out`` (raw frames, one event file per
    threshold, SYNTHETIC.json); the same seed gives byte-identical files. ``release``: 1 = list of
    dicts (Zenodo 6556273), 2 = pandas DataFrame (Zenodo 7050094). ``progress``:
    ``progress(done, total, phase)`` over 27 x ``repetitions`` samples ("generating frames") then
    1 + len(thresholds) files ("encoding and writing"), one count (None: none)."""
    from pathlib import Path

    from snncc.data.synth_set import write_synthetic_set
    from snncc.data.thresholds import parse_thresholds
    from snncc.errors import SnnccError

    for name, value, low, high in (("--repetitions", repetitions, 1, None), ("--release", release, 1, 2),
                                   ("--generator-version", generator_version, 1, 2)):
        if value < low or (high is not None and value > high):
            raise SnnccError(f"must be >= {low}" + (f" and <= {high}" if high is not None else ""), field=name)
    ths = parse_thresholds(thresholds)
    samples, total = 27 * repetitions, 27 * repetitions + 1 + len(ths)
    written = [0]

    def on_frames(k: int) -> None:
        if progress is not None:
            progress(k, total, "generating frames")

    def on_file() -> None:
        written[0] += 1
        if progress is not None:
            progress(samples + written[0], total, "encoding and writing")

    if progress is not None:
        progress(0, total, "generating frames")
    record = write_synthetic_set(Path(out), repetitions, seed, release, ths, generator_version,
                                 on_frames=None if progress is None else on_frames,
                                 on_file=None if progress is None else on_file)
    return SynthResult(**record)
