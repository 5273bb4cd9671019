"""Data for a search: the events loaded once, binned at each trial's ``time_bin_size`` on demand.

A directory of published Braille files (``snncc data synth`` or the Zenodo releases): the events
of the threshold (``data_braille_letters_th_<th>.pkl``), else the raw frames sigma-delta encoded;
binned by the rule of ``snncc data encode`` (``snncc.data.binning``). An encoded ``.npz`` (``snncc
data encode``) is binned already: time_bin_size is then pinned to its bin (``fixed_bin_ms``).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from snncc.errors import SnnccError

CACHE_SIZE = 3   # binned copies kept in memory (one per recent time_bin_size)


@dataclass
class EventSource:
    """Events and labels of one threshold; ``binned(bin_ms)`` gives a ``TrainingData``."""

    path: str
    threshold: int
    labels: np.ndarray
    events: object | None = None          # snncc.data.sigma_delta.Events (directory input)
    record_ms: float = 1350.0
    synthetic: bool = False
    fixed: object | None = None           # TrainingData of an encoded .npz
    _cache: "OrderedDict[float, object]" = field(default_factory=OrderedDict, repr=False)

    @property
    def fixed_bin_ms(self) -> float | None:
        if self.fixed is None:
            return None
        return float(self.fixed.meta.get("time_bin_size_ms") or 0) or None

    def binned(self, bin_ms: float):
        """The data binned at ``bin_ms`` (cached), as ``snncc.training.training_set.TrainingData``."""
        from snncc.data.binning import bin_events, n_bins_for
        from snncc.data.letters import CLASSES
        from snncc.training.training_set import TrainingData

        bin_ms = float(bin_ms)
        if self.fixed is not None:
            if self.fixed_bin_ms is None or not math.isclose(bin_ms, self.fixed_bin_ms):
                raise SnnccError(f"this .npz is binned at {self.fixed_bin_ms} ms; searching time_bin_size needs a "
                                 "directory of published Braille files", file=self.path, field="time_bin_size")
            return self.fixed
        if bin_ms in self._cache:
            self._cache.move_to_end(bin_ms)
            return self._cache[bin_ms]
        n_bins = n_bins_for(self.record_ms, bin_ms)
        try:
            x = bin_events(self.events, bin_ms, n_bins)
        except SnnccError as err:
            raise err.with_file(self.path)
        meta = {"kind": "events", "threshold": self.threshold, "time_bin_size_ms": bin_ms, "dt_s": bin_ms / 1000.0,
                "n_steps": n_bins, "classes": list(CLASSES), "synthetic": self.synthetic, "record_ms": self.record_ms,
                "binned_by": "snncc hpo (snncc data encode's rule)"}
        data = TrainingData(torch.from_numpy(x), torch.from_numpy(self.labels.astype(np.int64)), meta, self.path)
        self._cache[bin_ms] = data
        while len(self._cache) > CACHE_SIZE:
            self._cache.popitem(last=False)
        return data

    @property
    def channels(self) -> int:
        """Input channels of the binned data (ON and OFF per taxel, or the encoded set's own)."""
        return int(self.fixed.inputs.shape[-1]) if self.fixed is not None else 2 * int(self.events.n_taxels)

    def facts(self) -> dict:
        return {"path": self.path, "threshold": self.threshold, "samples": int(self.labels.shape[0]),
                "synthetic": self.synthetic, "record_ms": self.record_ms, "fixed_bin_ms": self.fixed_bin_ms}


def load_source(path: str | Path, threshold: int) -> EventSource:
    """Events of ``threshold`` from a directory of published files, or an encoded ``.npz``."""
    from snncc.data import braille_files, formats
    from snncc.data.binning import record_ms
    from snncc.data.sigma_delta import encode

    path = Path(path)
    if not path.exists():
        raise SnnccError("no such file or directory", file=str(path), field="--data")
    if path.is_file():
        from snncc.data.dataset_file import load_dataset
        from snncc.training.training_set import load_training_data

        _, _, meta = load_dataset(path)
        bin_ms = meta.get("time_bin_size_ms")
        if bin_ms is None:
            raise SnnccError("an encoded data set must state time_bin_size_ms (snncc data encode)", file=str(path),
                             field="meta.time_bin_size_ms")
        data = load_training_data(path, "rsnn", threshold, float(bin_ms))
        return EventSource(str(path), threshold, data.labels.numpy(), synthetic=bool(meta.get("synthetic")),
                           fixed=data)
    braille_files.require_exists(path)
    synthetic = braille_files.synthetic_info(path) is not None
    ev_path = braille_files.events_file(path, threshold)
    raw_path = braille_files.raw_file(path)
    rs = formats.load_raw(raw_path) if raw_path is not None else None
    rec = float(record_ms(rs.raw.shape[1])) if rs is not None else 1350.0   # the paper's 54 frames at 40 Hz
    if ev_path is not None:
        es = formats.load_events(ev_path)
        return EventSource(str(path), threshold, np.asarray(es.labels), es.events, rec, synthetic)
    if rs is None:
        raise SnnccError(f"neither {formats.events_name(threshold)} nor {formats.RAW_NAME} here", file=str(path),
                         field="--data")
    return EventSource(str(path), threshold, np.asarray(rs.labels), encode(rs.inverted(), threshold), rec, synthetic)
