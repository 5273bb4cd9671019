"""``snncc data nir``: SYNTHETIC Braille letters in the NIR paper's layout, labelled (``snncc.data.nir_letters``)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from snncc.errors import SnnccError, one_line

if TYPE_CHECKING:
    from rich.console import Console


@dataclass
class NirLettersResult:
    out: str
    samples: int
    steps: int
    channels: int
    classes: list[str]
    seed: int
    synthetic: bool
    events_per_sample: float
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        from dataclasses import asdict

        return asdict(self)

    def render_text(self, console: Console) -> None:
        console.print(f"wrote {self.samples} SYNTHETIC samples of {self.steps} steps x {self.channels} channels "
                      f"(letters {', '.join(self.classes)}; seed {self.seed}; {self.events_per_sample:.0f} events per "
                      f"sample) to {one_line(self.out)}", markup=False)
        for note in self.notes:
            console.print(f"note: {note}", markup=False)


def data_nir(*, out: str | os.PathLike, samples: int = 700, seed: int = 0, steps: int = 256) -> NirLettersResult:
    """``samples`` SYNTHETIC letters (Space, A, E, I, O, U, Y, balanced) as the NIR paper's Braille graphs take them:
    ON and OFF events of threshold 1 merged per taxel (12 channels), the 1.35 s recording cut into ``steps`` steps;
    written to ``out`` (.npz: inputs, labels, classes, synthetic), what ``check --data`` and ``compare --data``
    read."""
    from pathlib import Path

    from snncc.data.nir_letters import write_nir_letters

    if Path(out).suffix.lower() != ".npz":
        raise SnnccError("the letters are written as an .npz: name the file .npz", file=str(out), field="--out")
    for name, value in (("--samples", samples), ("--steps", steps)):
        if value < 1:
            raise SnnccError("must be a whole number >= 1", field=name)
    from snncc.limits import check_memory

    check_memory(int(samples) * int(steps) * 12 * 2, f"{samples:,} samples of {steps} steps", field="--samples")
    record = write_nir_letters(out, samples, seed, steps)
    return NirLettersResult(**record, notes=[
        "SYNTHETIC: snncc's calibrated generator, not the NIR paper's recordings; accuracy on these letters is not "
        "the paper's test accuracy"])
