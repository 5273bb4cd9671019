"""``snncc data frames`` as a function: the inverted raw frames as a frame data set (for the LSTM)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

from snncc.errors import one_line

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.data.encoding import EncodedSet


@dataclass
class FramesResult:
    """``encoded``: the ``EncodedSet`` (inputs (N, T, 12) float32, 0 = rest, 255 = full load; labels;
    meta); ``written``: the files (OUT, and OUT_train / OUT_test for a split)."""

    encoded: EncodedSet
    written: list[str]

    def as_dict(self) -> dict:
        """What ``snncc data frames --json`` prints: the set's summary."""
        from snncc.records import to_jsonable

        return to_jsonable(self.encoded.summary(self.written))

    def render_text(self, console: Console) -> None:
        n, t = self.encoded.inputs.shape[:2]
        console.print(f"{n} samples x {t} frames x 12 taxels -> {', '.join(map(one_line, self.written))}",
                      markup=False)


def data_frames(src: str | os.PathLike, *, out: str | os.PathLike, split_test: float | None = None,
                seed: int = 0) -> FramesResult:
    """Write the inverted frames of ``src`` (a directory with the raw-frame file, or that .pkl) into
    ``out`` (.npz); ``split_test`` also writes a stratified OUT_train / OUT_test split."""
    from pathlib import Path

    from snncc.data.encoding import frame_set, write_with_split
    from snncc.verbs.data_encode import check_split

    check_split(split_test)
    encoded = frame_set(Path(src))
    return FramesResult(encoded, write_with_split(Path(out), encoded, split_test, seed))
