"""Sigma-delta thresholds as users give them: ``"1,2,5,10"`` or a sequence of numbers."""

from __future__ import annotations

import math
from typing import Iterable

from snncc.errors import SnnccError


def parse_thresholds(value: str | Iterable[float], field: str = "--thresholds") -> list[float]:
    """Sorted distinct positive finite thresholds; a string is comma-separated numbers."""
    items = value.split(",") if isinstance(value, str) else list(value)
    try:
        ths = [float(x) for x in items if not isinstance(x, str) or x.strip()]
    except (TypeError, ValueError):
        raise SnnccError(f"expected comma-separated numbers, got {value!r}", field=field) from None
    if not ths or any(not math.isfinite(t) or t <= 0 for t in ths):
        raise SnnccError("thresholds must be positive numbers", field=field)
    return sorted(set(ths))


def threshold_key(th: float) -> str:
    """A threshold as a JSON key and in text: ``1``, ``2.5``."""
    return f"{th:g}"
