"""Verbs whose work lands in a later issue say so plainly instead of pretending."""

from __future__ import annotations

from snncc.errors import SnnccError


def not_built(verb: str, what: str) -> None:
    raise SnnccError(f"{what} is not built in this version of snncc yet", field=f"snncc {verb}")
