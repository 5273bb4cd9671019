"""The paper authors' hyper-parameter file: one ``key value`` pair a line.

Keys (all required, no others): scale time_bin_size nb_input_copies tau_mem tau_ratio
fwd_weight_scale weight_scale_factor reg_spikes reg_neurons. ``tau_mem`` in seconds,
``time_bin_size`` in ms, ``tau_syn = tau_mem / tau_ratio``. Blank lines and ``#`` comments are
ignored; ``key: value`` and ``key = value`` are accepted too.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

from snncc.errors import SnnccError
from snncc.limits import check_time_steps

KEYS = ("scale", "time_bin_size", "nb_input_copies", "tau_mem", "tau_ratio",
        "fwd_weight_scale", "weight_scale_factor", "reg_spikes", "reg_neurons")
POSITIVE = ("scale", "time_bin_size", "nb_input_copies", "tau_mem", "tau_ratio")
RECORDING_LENGTH_S = 1.35  # the Braille recordings: 54 frames at 40 Hz


@dataclass(frozen=True)
class PaperParams:
    scale: float
    time_bin_size: float
    nb_input_copies: int
    tau_mem: float
    tau_ratio: float
    fwd_weight_scale: float
    weight_scale_factor: float
    reg_spikes: float
    reg_neurons: float

    @property
    def dt(self) -> float:
        """Time step in seconds (time_bin_size is in ms)."""
        return self.time_bin_size / 1000.0

    @property
    def tau_syn(self) -> float:
        return self.tau_mem / self.tau_ratio

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in KEYS}


def parse_params(text: str, source: str = "<params>") -> PaperParams:
    values: dict[str, float] = {}
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [p for p in re.split(r"[\s:=,]+", line) if p]
        if len(parts) != 2:
            raise SnnccError("each line must be 'key value'", file=source, field=f"line {lineno}")
        key, value = parts
        if key not in KEYS:
            raise SnnccError(f"unknown key (expected one of {', '.join(KEYS)})", file=source, field=key)
        if key in values:
            raise SnnccError("key given twice", file=source, field=key)
        try:
            number = float(value)
        except ValueError:
            raise SnnccError(f"value {value!r} is not a number", file=source, field=key) from None
        if not math.isfinite(number):
            raise SnnccError("value must be finite", file=source, field=key)
        values[key] = number
    missing = [k for k in KEYS if k not in values]
    if missing:
        raise SnnccError("missing key (all of the paper's nine keys are required)", file=source, field=missing[0])
    for key in POSITIVE:
        if values[key] <= 0:
            raise SnnccError("must be positive", file=source, field=key)
    for key in ("fwd_weight_scale", "weight_scale_factor", "reg_spikes", "reg_neurons"):
        if values[key] < 0:
            raise SnnccError("must not be negative", file=source, field=key)
    check_time_steps(RECORDING_LENGTH_S * 1000.0 / values["time_bin_size"],
                     f"time_bin_size {values['time_bin_size']:g} ms over the {RECORDING_LENGTH_S} s Braille recording",
                     file=source, field="time_bin_size")
    copies = values["nb_input_copies"]
    if copies != int(copies):
        raise SnnccError("must be a whole number", file=source, field="nb_input_copies")
    values["nb_input_copies"] = int(copies)
    return PaperParams(**values)


def load_params(path: str | Path) -> PaperParams:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as ex:
        raise SnnccError(f"cannot read parameters file ({type(ex).__name__})", file=str(path), field="params") from None
    return parse_params(text, source=str(path))


def format_params(p: PaperParams) -> str:
    """The file text for ``p`` (the inverse of ``parse_params``)."""
    return "".join(f"{k} {getattr(p, k)}\n" for k in KEYS)
