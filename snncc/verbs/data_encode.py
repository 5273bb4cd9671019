"""``snncc data encode`` as a function: sigma-delta encode and time-bin Braille data into a model input set."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING

from snncc.errors import one_line
from snncc.verbs import VerbProgress

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.data.encoding import EncodedSet


@dataclass
class EncodeResult:
    """``encoded``: the ``EncodedSet`` (inputs (N, T, 24) uint8, labels, meta); ``written``: the
    files (OUT, and OUT_train / OUT_test for a split); ``bin_ms``: the bin size used."""

    encoded: EncodedSet
    written: list[str]
    bin_ms: float

    def as_dict(self) -> dict:
        """What ``snncc data encode --json`` prints: the set's summary."""
        from snncc.records import to_jsonable

        return to_jsonable(self.encoded.summary(self.written))

    def render_text(self, console: Console) -> None:
        inputs, meta = self.encoded.inputs, self.encoded.meta
        console.print(f"{inputs.shape[0]} samples x {inputs.shape[1]} bins x 24 channels (th {meta['threshold']:g}, "
                      f"bin {self.bin_ms:g} ms) -> {', '.join(map(one_line, self.written))}", markup=False)
        before, after = meta["events_before_binning"], meta["events_after_binning"]
        lost = 100.0 * (1 - after / before) if before else 0.0
        console.print(f"events: {before} before binning, {after} after ({lost:.1f} % merged)"
                      + ("   (synthetic data)" if meta["synthetic"] else ""))


def data_encode(src: str | os.PathLike, *, out: str | os.PathLike, threshold: float | None = None,
                bin_ms: float = 5.0, prefer: str = "auto", record_ms: float | None = None,
                split_test: float | None = None, seed: int = 0, progress: VerbProgress | None = None) -> EncodeResult:
    """Encode ``src`` (a directory of published files or one .pkl) into ``out`` (.npz).

    Events follow the authors' rule (``snncc.data.encoding``); ``bin_ms`` is ``--bin``, ``prefer``
    is ``--from`` (auto, events or raw); ``split_test`` also writes a stratified OUT_train /
    OUT_test split seeded by ``seed``. ``progress``: ``progress(done, 2, "loading / encoding")``
    after loading and after encoding (None: none).
    """
    from pathlib import Path

    from snncc.data.encoding import encode_events, write_with_split
    from snncc.verbs import counting

    check_split(split_test)
    advanced = counting(progress, 2, "loading / encoding")
    tick = None if advanced is None else (lambda: advanced(1))
    if progress is not None:
        progress(0, 2, "loading / encoding")
    encoded = encode_events(Path(src), threshold, bin_ms, prefer, record_ms, progress=tick)
    if tick is not None:
        tick()
    return EncodeResult(encoded, write_with_split(Path(out), encoded, split_test, seed), bin_ms)


def check_split(split_test: float | None) -> None:
    """``--split-test`` is a test fraction in [0.01, 0.99] (or None: no split)."""
    from snncc.errors import SnnccError

    if split_test is not None and not 0.01 <= split_test <= 0.99:
        raise SnnccError("must be between 0.01 and 0.99", field="--split-test")
