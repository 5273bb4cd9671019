"""What a user can tell a frontend that a file cannot (``LoadOptions``), and the rule that refuses an
option the file's format cannot use."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from snncc.errors import SnnccError


@dataclass
class LoadOptions:
    """What a user can tell a frontend that a file cannot: parameters file, dt, reset mode."""

    params: Path | None = None
    dt: float | None = None
    reset: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)


# which input formats each load option applies to (a given option the file cannot use is refused)
OPTION_USE = {
    "params": ("--params", "a SpyTorch weight list (the authors' [W_in, W_out(, V_rec)])"),
    "dt": ("--dt", "NIR graphs (NIR stores no time step)"),
    "reset": ("--reset", "NIR graphs (NIR does not say whether a reset subtracts)"),
}


def refuse_options(options: LoadOptions | None, accepted: tuple[str, ...], what: str, path: str | Path) -> None:
    """Refuse every load option given by the user that a file of kind ``what`` cannot use."""
    if options is None:
        return
    for key, (flag, applies_to) in OPTION_USE.items():
        if key not in accepted and getattr(options, key) is not None:
            raise SnnccError(f"does not apply to {what}; it applies only to {applies_to}", file=str(path), field=flag)
