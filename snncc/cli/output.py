"""Printing reports: rich text for people, JSON for tools (same record, two renderings)."""

from __future__ import annotations

import json
from typing import Any

from rich.console import Console

console = Console(highlight=False)
err_console = Console(stderr=True, highlight=False)


def print_json(record: Any) -> None:
    from snncc.records import to_jsonable   # numpy-aware; imported only when JSON is printed

    print(json.dumps(to_jsonable(record), indent=2, sort_keys=False))
