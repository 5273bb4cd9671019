"""The model options every command that takes a model file offers, declared once (``snncc.frontends.LoadOptions``).

    --params   the authors' parameters file for a SpyTorch weight list
    --dt       the time step, for formats that store none (NIR)
    --reset    the reset rule, for formats that do not say (NIR): zero | subtract | zero-delayed

compile, check, compare, inspect, export, map, report and emulate take a model file (map, report and emulate
also take written artefacts, for which the model options are refused: compile fixed the model). Each
command's signature uses ``params_option()``, ``dt_option()`` and ``reset_option()``.
"""

from __future__ import annotations

from typing import Any

import typer

PARAMS_HELP = "The authors' parameters file (key value per line) for a SpyTorch weight list."
DT_HELP = "Time step in seconds, for model formats that do not store one (NIR)."
RESET_HELP = ("Reset rule, for model formats that do not say (NIR): zero | subtract | zero-delayed (snnTorch's "
              "one-step-late zero reset).")


def params_option() -> Any:
    return typer.Option(None, "--params", help=PARAMS_HELP)


def dt_option() -> Any:
    return typer.Option(None, "--dt", help=DT_HELP)


def reset_option() -> Any:
    return typer.Option(None, "--reset", help=RESET_HELP)
