"""Finding the published Braille files in a directory (or taking one .pkl) and the synthetic marker.

A directory holds ``data_braille_letters_raw.pkl`` and/or ``data_braille_letters_th_{th}.pkl``
(the Zenodo layout). ``snncc data synth`` also writes ``SYNTHETIC.json`` beside them (generator
parameters and seed), so every later product can record ``synthetic: true``; the real files have
no such marker.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from snncc.atomic import record_input
from snncc.data.formats import RAW_NAME, events_name
from snncc.errors import SnnccError

MARKER = "SYNTHETIC.json"
_TH_RE = re.compile(r"_th_?(\d+(?:\.\d+)?)\.pkl$")


def threshold_from_name(path: Path) -> float | None:
    m = _TH_RE.search(path.name)
    return float(m.group(1)) if m else None


def synthetic_info(path: Path) -> dict | None:
    """The generator record next to ``path`` (a file or directory), or None for real data."""
    d = path if path.is_dir() else path.parent
    marker = d / MARKER
    if not marker.is_file():
        return None
    record_input(marker)
    try:
        info = json.loads(marker.read_text())
    except (OSError, json.JSONDecodeError):
        raise SnnccError("unreadable synthetic-data marker (JSON expected)", file=str(marker), field="format") from None
    return info if isinstance(info, dict) else None


def raw_file(src: Path) -> Path | None:
    """The raw-frame file of ``src`` (a directory or a .pkl), or None."""
    if src.is_dir():
        p = src / RAW_NAME
        return p if p.is_file() else None
    return src


def events_file(src: Path, threshold: float) -> Path | None:
    if src.is_dir():
        p = src / events_name(threshold)
        return p if p.is_file() else None
    return None


def require_exists(src: Path) -> Path:
    if not src.exists():
        raise SnnccError("no such file or directory", file=str(src), field="path")
    if src.is_dir() and not (src / RAW_NAME).is_file() and not any(src.glob("data_braille_letters_th_*.pkl")):
        raise SnnccError(f"no published Braille files here (expected {RAW_NAME} or "
                         "data_braille_letters_th_<th>.pkl)", file=str(src), field="path")
    return src
