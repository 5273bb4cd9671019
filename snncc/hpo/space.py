"""The search space of the paper's HPO: its nine hyper-parameters, ranges stated here and only here.

The paper (its "Hyperparameter optimization" section and Table "hpo") names the nine
hyper-parameters but not their ranges; the ranges below are OUR CHOICE, each bracketing the
paper's four per-threshold presets (``snncc.training.presets``) by a factor of a few:

| hyper-parameter       | range            | scale  | paper presets (th 1 / 2 / 5 / 10) |
|-----------------------|------------------|--------|-----------------------------------|
| scale                 | 1 .. 50          | log    | 5 / 15 / 10 / 10                  |
| time_bin_size (ms)    | 2 .. 10, integer | linear | 5 / 3 / 3 / 5                     |
| nb_input_copies       | 1 .. 16, integer | log    | 2 / 8 / 4 / 2                     |
| tau_mem (s)           | 0.01 .. 0.2      | log    | 0.06 / 0.05 / 0.07 / 0.07         |
| tau_ratio             | 2 .. 20          | log    | 10 / 10 / 10 / 10                 |
| fwd_weight_scale      | 0.1 .. 10        | log    | 1 / 1 / 1.5 / 4                   |
| weight_scale_factor   | 0.001 .. 0.1     | log    | 0.01 / 0.02 / 0.035 / 0.015       |
| reg_spikes            | 1e-4 .. 1e-2     | log    | 0.004 / 0.0015 / 0.001 / 0.0015   |
| reg_neurons           | 0 .. 1e-5        | linear | 1e-6 / 0 / 0 / 0                  |

time_bin_size stops at 2 ms by our choice (1 ms means 1350 steps per sample: slow to train).
Step 2 (grid) takes time_bin_size from the integers and nb_input_copies from the ladder
``COPIES_LADDER``, ``span`` rungs either side of step 1's best (our choice: 1, a 3 x 3 grid).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from snncc.errors import InternalError, SnnccError
from snncc.frontends.params import KEYS, PaperParams
from snncc.training.presets import PRESETS


@dataclass(frozen=True)
class Range:
    """One hyper-parameter's range: ``low <= value <= high`` (integers when ``integer``)."""

    name: str
    low: float
    high: float
    log: bool = False
    integer: bool = False

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def fixed(self) -> bool:
        return self.low == self.high

    def contains(self, value: float) -> bool:
        return self.low <= value <= self.high

    def distribution(self):
        """The Optuna distribution of this range."""
        from optuna.distributions import FloatDistribution, IntDistribution

        if self.integer:
            return IntDistribution(int(self.low), int(self.high), log=self.log)
        return FloatDistribution(float(self.low), float(self.high), log=self.log)


SEARCH_SPACE: dict[str, Range] = {r.name: r for r in (
    Range("scale", 1.0, 50.0, log=True),
    Range("time_bin_size", 2, 10, integer=True),
    Range("nb_input_copies", 1, 16, log=True, integer=True),
    Range("tau_mem", 0.01, 0.2, log=True),
    Range("tau_ratio", 2.0, 20.0, log=True),
    Range("fwd_weight_scale", 0.1, 10.0, log=True),
    Range("weight_scale_factor", 0.001, 0.1, log=True),
    Range("reg_spikes", 1e-4, 1e-2, log=True),
    Range("reg_neurons", 0.0, 1e-5),
)}
if tuple(SEARCH_SPACE) != KEYS:   # the search space names every parameter, in the parameters file's order
    raise InternalError(f"the search space's keys {tuple(SEARCH_SPACE)} are not the parameters' {KEYS}", field="hpo")

GRID_KEYS = ("time_bin_size", "nb_input_copies")   # the two that set the operations per inference
COPIES_LADDER = (1, 2, 3, 4, 6, 8, 12, 16)
POSITIVE = ("scale", "time_bin_size", "nb_input_copies", "tau_mem", "tau_ratio")


def parse_range(item: str) -> Range:
    """``"tau_mem=0.02:0.1"`` -> a Range (log and integer as in ``SEARCH_SPACE``); ``"tau_ratio=10"`` fixes it."""
    key, sep, value = item.partition("=")
    key = key.strip()
    if not sep or key not in SEARCH_SPACE:
        raise SnnccError(f"must be KEY=LOW:HIGH or KEY=VALUE with KEY one of {', '.join(KEYS)}", field=f"--range {item}")
    low_text, colon, high_text = value.partition(":")
    try:
        low = float(low_text)
        high = float(high_text) if colon else low
    except ValueError:
        raise SnnccError("bounds must be numbers", field=f"--range {item}") from None
    base = SEARCH_SPACE[key]
    return check_range(replace(base, low=low, high=high), field=f"--range {item}")


def check_range(r: Range, field: str | None = None) -> Range:
    """``r`` if it is a valid range for its hyper-parameter, else a one-line error."""
    field = field or r.name
    if not (math.isfinite(r.low) and math.isfinite(r.high)):
        raise SnnccError("bounds must be finite", field=field)
    if r.low > r.high:
        raise SnnccError(f"low {r.low:g} is above high {r.high:g}", field=field)
    if r.name in POSITIVE and r.low <= 0:
        raise SnnccError("must be positive", field=field)
    if r.low < 0:
        raise SnnccError("must not be negative", field=field)
    if r.log and r.low <= 0:
        raise SnnccError("a log-scale range needs a positive low bound", field=field)
    if r.integer and (r.low != int(r.low) or r.high != int(r.high)):
        raise SnnccError("bounds must be whole numbers", field=field)
    if r.integer:
        r = replace(r, low=int(r.low), high=int(r.high))
    return r


def search_space(ranges: list[str] | None = None) -> dict[str, Range]:
    """``SEARCH_SPACE`` with ``--range`` overrides applied (each key at most once)."""
    space = dict(SEARCH_SPACE)
    seen: set[str] = set()
    for item in ranges or []:
        r = parse_range(item)
        if r.name in seen:
            raise SnnccError("range given twice", field=f"--range {r.name}")
        seen.add(r.name)
        space[r.name] = r
    return space


def space_as_dict(space: dict[str, Range]) -> dict[str, dict]:
    return {k: r.as_dict() for k, r in space.items()}


def space_from_dict(d: dict[str, dict]) -> dict[str, Range]:
    return {k: Range(**v) for k, v in d.items()}


def suggest(trial, space: dict[str, Range], fixed: dict[str, float] | None = None) -> dict[str, float]:
    """The nine values for ``trial``: ``fixed`` ones as given, the others suggested from ``space``."""
    fixed = fixed or {}
    values: dict[str, float] = {}
    for key in KEYS:
        if key in fixed:
            values[key] = fixed[key]
            continue
        r = space[key]
        if r.fixed:
            values[key] = int(r.low) if r.integer else r.low
        elif r.integer:
            values[key] = trial.suggest_int(key, int(r.low), int(r.high), log=r.log)
        else:
            values[key] = trial.suggest_float(key, r.low, r.high, log=r.log)
    return values


def preset_in_space(threshold: int, space: dict[str, Range]) -> dict[str, float] | None:
    """The paper's preset for ``threshold`` as trial parameters, or None when outside ``space``."""
    preset = PRESETS.get(threshold)
    if preset is None:
        return None
    values = preset.as_dict()
    if not all(space[k].contains(v) for k, v in values.items()):
        return None
    return {k: v for k, v in values.items() if not space[k].fixed}


def _neighbours(ladder: list[float], best: float, span: int) -> list[float]:
    rungs = sorted(set(ladder) | {best})
    i = rungs.index(best)
    return rungs[max(0, i - span): i + span + 1]


def grid_around(best: dict[str, float], space: dict[str, Range], span: int = 1) -> dict[str, list]:
    """Step 2's grid: time_bin_size and nb_input_copies, ``span`` rungs either side of ``best``."""
    if span < 0:
        raise SnnccError("must be >= 0", field="--grid-span")
    tb, nc = space["time_bin_size"], space["nb_input_copies"]
    bins = list(range(int(math.ceil(tb.low)), int(math.floor(tb.high)) + 1)) or [tb.low]
    copies = [c for c in COPIES_LADDER if nc.low <= c <= nc.high] or [int(nc.low)]
    return {"time_bin_size": [int(v) if float(v).is_integer() else v
                              for v in _neighbours(bins, best["time_bin_size"], span)],
            "nb_input_copies": [int(v) for v in _neighbours(copies, int(best["nb_input_copies"]), span)]}


def as_params(values: dict[str, float]) -> PaperParams:
    """Nine values -> PaperParams (validated like a parameters file)."""
    from snncc.training.presets import with_overrides

    return with_overrides(PRESETS[1], {k: values[k] for k in KEYS})
