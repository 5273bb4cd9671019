"""``snncc analyse ttc`` as a function: time to classification of trained models, JSON and one figure."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from snncc.errors import one_line

if TYPE_CHECKING:
    from rich.console import Console

    from snncc.training.ttc import TTCRecord


@dataclass
class TTCResult:
    """``records``: one ``TTCRecord`` per model (fractions, accuracy per fraction, per-sample TTC,
    mean and median TTC, final accuracy, share never correct, method, notes); ``rule``: the TTC
    rule; ``output`` / ``figure``: the files written (or None)."""

    records: list[TTCRecord]
    rule: str
    output: str | None = None
    figure: str | None = None

    def as_dict(self) -> dict:
        """What ``snncc analyse ttc --json`` prints (and ``--output`` holds): the rule and the models."""
        from snncc.records import to_jsonable

        return to_jsonable({"rule": self.rule, "models": [r.as_dict() for r in self.records]})

    def render_text(self, console: Console) -> None:
        from snncc.training.ttc import ttc_table

        console.print(ttc_table(self.records), markup=False, soft_wrap=True)
        for r in self.records:
            console.print(f"{r.model}: {r.method}; {'; '.join(r.notes)}; data {r.data}", markup=False, soft_wrap=True)
        for path in (self.output, self.figure):
            if path is not None:
                console.print(f"wrote {one_line(path)}", markup=False)


def analyse_ttc(models: Sequence[str | os.PathLike], *, data: Sequence[str | os.PathLike], split: str = "test",
                output: str | os.PathLike | None = None, figure: str | os.PathLike | None = None) -> TTCResult:
    """TTC of each checkpoint in ``models`` on the first set in ``data`` of its encoding; ``split``:
    test (each checkpoint's own test samples) or all. ``output``: the records as JSON (atomically);
    ``figure``: accuracy vs signal fraction of all models (.png, .pdf or .svg)."""
    import json

    from snncc.atomic import write_text_atomic
    from snncc.training.ttc import RULE, check_figure_path, plot_records, ttc_of_checkpoints, ttc_payload

    if figure is not None:
        check_figure_path(Path(figure))
    records = ttc_of_checkpoints([str(m) for m in models], [str(d) for d in data], split)
    if output is not None:
        write_text_atomic(output, json.dumps(ttc_payload(records), indent=2) + "\n")
    if figure is not None:
        plot_records(records, Path(figure))
    return TTCResult(records, RULE, None if output is None else str(output), None if figure is None else str(figure))
