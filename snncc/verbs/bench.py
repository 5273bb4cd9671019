"""``snncc bench``: measured per-sample latency (and power) of written artefacts, the paper's protocol.

Warm-up: the whole data set ``warmup_passes`` times in batches of 64; timing: ``timed_passes`` passes
at batch 1, repeated ``repeats`` times (median and spread). ``power`` samples the board's main rail
during each timed repeat. Several artefacts are timed side by side (ratios to the first).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from snncc.errors import SnnccError
from snncc.verbs import VerbProgress

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.targets.base import Record


@dataclass
class BenchResult:
    """One artefact's benchmark record, as the command prints it (the target renders it)."""

    artefact: str
    repeats: int
    record: Record

    def as_dict(self) -> dict[str, object]:
        return dict(self.record.as_dict())

    def render_text(self, console: Console) -> None:
        self.record.render_text(console)


@dataclass
class ComparisonResult:
    """Several artefacts timed side by side (the target renders the comparison)."""

    comparison: Record

    def as_dict(self) -> dict[str, object]:
        return dict(self.comparison.as_dict())

    def render_text(self, console: Console) -> None:
        self.comparison.render_text(console)


def bench_artefacts(artefacts: str | Path | list[str | Path], *, target: str | None = None, data: str | Path | None = None,
                    samples: int = 64, power: bool = False, power_root: str | Path = Path("/"), rail: str = "VDD_IN",
                    repeats: int = 3, warmup_passes: int = 6, timed_passes: int = 6, stream: bool = False,
                    backend: str = "auto", progress: VerbProgress | None = None) -> BenchResult | ComparisonResult:
    """Benchmark one artefact (``BenchResult``) or several side by side (``ComparisonResult``)."""
    from snncc.artefacts import target_for
    from snncc.targets import capability

    paths = [Path(a) for a in ([artefacts] if isinstance(artefacts, (str, Path)) else artefacts)]
    for name, value in (("--repeats", repeats), ("--warmup-passes", warmup_passes + 1),
                        ("--timed-passes", timed_passes), ("--samples", samples)):
        if value < 1:
            raise SnnccError("must be >= 1 (warm-up passes >= 0)", field=name)
    owners = [target_for(p, target, "bench") for p in paths]
    if len({t.name for t in owners}) > 1:
        raise SnnccError(f"the artefacts belong to different targets ({', '.join(sorted({t.name for t in owners}))}); "
                         "bench times one target's artefacts side by side", field="artefacts")
    bench = capability(owners[0], "bench")
    record = bench(paths, data=None if data is None else Path(data), samples=samples, power=power,
                   power_root=Path(power_root), rail=rail, repeats=repeats, warmup_passes=warmup_passes,
                   timed_passes=timed_passes, stream=stream, backend=backend, progress=progress)
    if len(paths) > 1:
        return ComparisonResult(record)
    return BenchResult(str(paths[0]), repeats, record)
